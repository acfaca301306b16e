// Where obstacle_detector's reading noise σ_d comes from, as users run it: the weights' σ_d for
// the recording's scenario (light from --light, preset from the recording) when they hold one,
// else the recording's own frames, else the config. A simulated High Accuracy recording of the
// calibrated sensor (config/sensor_calibrated.yaml: σ_d 0.0698 px) with three people, and
// weights written here: one group per preset, a bias model that corrects nothing and a
// placement σ of 1 mm, so that the margin's σ is the reading noise and σ_d shows in it.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "io/weights_yaml.h"
#include "support/tools.h"

namespace depthbias {
namespace {

namespace fs = std::filesystem;

using test_support::Bin;
using test_support::ReadFile;
using test_support::RunShell;

const std::string kSensor = DEPTHBIAS_SOURCE_DIR "/config/sensor_calibrated.yaml";
constexpr double kSensorHaSigmaPx = 0.06983629732;  // daylight/HA of kSensor

constexpr char kProtocol[] = R"(protocol:
  presets: [HA]
  emitters: ["on"]
  lights: [daylight]
  frames: 12
scene:
  camera_height_m: 1.0
  panel: off
  obstacles:
    - {kind: person, range_m: 5, azimuth_deg: -10}
    - {kind: person, range_m: 9, azimuth_deg: 10}
    - {kind: person, range_m: 13, azimuth_deg: 0}
)";

// One group per preset; `ha_sigma_px` / `hd_sigma_px` > 0 give that group a disparity_noise.
std::string Weights(double ha_sigma_px, double hd_sigma_px) {
  std::string text =
      "schema: depthbias.weights/2\nmodel: disp_scale\nlambda: 0.001\nfocal_px: 640\n"
      "baseline_m: 0.095\ngroup_by: [light, preset]\nnear_guard: {near_m: 5, full_m: 7}\n"
      "noise_pooled: true\ngroups:\n";
  for (const auto& [preset, sigma_px] :
       std::vector<std::pair<std::string, double>>{{"HA", ha_sigma_px}, {"HD", hd_sigma_px}}) {
    text += "  - light: daylight\n    preset: " + preset +
            "\n    n: 16\n    weights: {delta_px: 0, k: 1}\n    rmse_m: 0.001\n"
            "    mae_m: 0.001\n    residual_std_m: 0.001\n"
            "    margin: {placement_m: 0.001, noise_per_m: 0}\n";
    if (sigma_px > 0) {
      std::ostringstream s;
      s.precision(17);
      s << sigma_px;
      text += "    disparity_noise: {sigma_px: " + s.str() + ", recordings: 16}\n";
    }
    text += "    covariance: [[0, 0], [0, 0]]\n";
  }
  return text;
}

struct Detections {
  std::string summary;
  std::vector<YAML::Node> lines;
};

class DetectorNoiseSource : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const char* app : {"simulate", "obstacle_detector"})
      ASSERT_TRUE(fs::exists(Bin(app))) << app << " is not built";
    // One folder per test: ctest runs the tests of this file in parallel.
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(DEPTHBIAS_BINARY_DIR) / "test_tmp" / (std::string("noise_source_") +
                                                          info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::ofstream(dir_ / "protocol.yaml") << kProtocol;
    const auto r = RunShell(Bin("simulate") + " --protocol " + (dir_ / "protocol.yaml").string() +
                                " --sensor " + kSensor + " --seed 7 --out-dir " +
                                (dir_ / "bags").string(),
                            dir_);
    ASSERT_EQ(r.code, 0) << r.err;
    bag_ = (dir_ / "bags" / "sim_daylight_emitter-on_obstacles_HA.bag").string();
    ASSERT_TRUE(fs::exists(bag_));
  }
  void TearDown() override { fs::remove_all(dir_ / "bags"); }

  // obstacle_detector with these weights on the HA recording.
  Detections Detect(const std::string& name, const std::string& weights) {
    const fs::path w = dir_ / (name + ".yaml"), out = dir_ / (name + ".jsonl");
    std::ofstream(w) << weights;
    const auto r = RunShell(Bin("obstacle_detector") + " --weights " + w.string() +
                                " --light daylight --k 2 --config " DEPTHBIAS_SOURCE_DIR
                                "/config/obstacle_detector.yaml --out " + out.string() + " " +
                                bag_,
                            dir_);
    EXPECT_EQ(r.code, 0) << name << ": " << r.err;
    Detections run;
    run.summary = r.out + r.err;
    std::istringstream lines(ReadFile(out));
    for (std::string line; std::getline(lines, line);) run.lines.push_back(YAML::Load(line));
    EXPECT_EQ(run.lines.size(), 12u) << name;
    return run;
  }

  // Every line gives this σ_d and source.
  static void ExpectEveryLine(const Detections& run, const std::string& from, double sigma_px,
                              double tolerance_px) {
    for (const YAML::Node& l : run.lines) {
      EXPECT_EQ(l["disparity_noise_from"].as<std::string>(), from);
      EXPECT_NEAR(l["disparity_noise_px"].as<double>(), sigma_px, tolerance_px);
    }
  }

  fs::path dir_;
  std::string bag_;
};

// (a) The weights hold σ_d for High Density only; the recording is High Accuracy: its σ_d comes
// from its own frames (the sensor's 0.0698 px), never from the other preset's value.
TEST_F(DetectorNoiseSource, AnotherPresetsSigmaIsNotUsed) {
  const Detections run = Detect("hd_only", Weights(0, 0.5));
  EXPECT_NE(run.summary.find("px from the recording ("), std::string::npos) << run.summary;
  EXPECT_EQ(run.summary.find("from the weights"), std::string::npos) << run.summary;
  ExpectEveryLine(run, "recording", kSensorHaSigmaPx, 0.1 * kSensorHaSigmaPx);
}

// (b) The weights' σ_d for the recording's scenario is used, said in the summary and every line,
// and it flows into the margin: weights whose σ_d is 10 times too small give the same
// obstacles with a visibly narrower σ and a safe range nearer to the corrected one.
TEST_F(DetectorNoiseSource, TheWeightsSigmaIsUsedAndFlowsIntoTheMargin) {
  const Detections right = Detect("right", Weights(kSensorHaSigmaPx, 0.15));
  EXPECT_NE(right.summary.find("sigma_d 0.0698363 px from the weights (daylight/HA, median of "
                               "16 recordings)"),
            std::string::npos)
      << right.summary;
  ExpectEveryLine(right, "weights", kSensorHaSigmaPx, 1e-6);
  const Detections broken = Detect("broken", Weights(kSensorHaSigmaPx / 10, 0.15));
  EXPECT_NE(broken.summary.find("px from the weights (daylight/HA"), std::string::npos)
      << broken.summary;
  ExpectEveryLine(broken, "weights", kSensorHaSigmaPx / 10, 1e-7);

  // σ_d changes the margin, not the detections: the same obstacles, frame by frame.
  ASSERT_EQ(right.lines.size(), broken.lines.size());
  int far = 0;
  double right_std = 0, broken_std = 0;
  for (size_t f = 0; f < right.lines.size(); ++f) {
    const YAML::Node& a = right.lines[f]["obstacles"];
    const YAML::Node& b = broken.lines[f]["obstacles"];
    ASSERT_EQ(a.size(), b.size()) << "frame " << f;
    for (size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i]["range_m"].as<double>(), b[i]["range_m"].as<double>());
      EXPECT_EQ(a[i]["corrected_range_m"].as<double>(), b[i]["corrected_range_m"].as<double>());
      EXPECT_LT(b[i]["std_m"].as<double>(), a[i]["std_m"].as<double>());
      // corrected − safe is the margin (k·σ) wherever the raw range does not cap the safe one.
      EXPECT_GE(b[i]["safe_range_m"].as<double>(), a[i]["safe_range_m"].as<double>());
      if (a[i]["range_m"].as<double>() > 8.0) {
        ++far;
        right_std += a[i]["std_m"].as<double>();
        broken_std += b[i]["std_m"].as<double>();
      }
    }
  }
  ASSERT_GE(far, 20) << "the people at 9 and 13 m in most of the 12 frames";
  // The reading σ is proportional to σ_d: beyond 8 m it dominates this margin (1 mm of placement
  // besides), so the broken weights' σ is several times narrower.
  EXPECT_LT(broken_std, 0.3 * right_std) << "mean σ beyond 8 m: right " << right_std / far
                                         << " m, broken " << broken_std / far << " m";
  std::printf("mean σ beyond 8 m (%d obstacles): σ_d %.4f px → %.4f m; σ_d %.5f px → %.4f m\n",
              far, kSensorHaSigmaPx, right_std / far, kSensorHaSigmaPx / 10, broken_std / far);
}

// (c) Weights written before σ_d was part of them (no disparity_noise key) load and the
// recording's frames give σ_d, as before.
TEST_F(DetectorNoiseSource, OldWeightsWithoutTheKeyFallBackToTheFrames) {
  const std::string old = Weights(0, 0);
  ASSERT_EQ(old.find("disparity_noise"), std::string::npos);
  for (const auto& g : io::ParseWeightsYaml(old, "old.yaml").groups)
    EXPECT_FALSE(g.disparity_noise.known);
  const Detections run = Detect("old", old);
  EXPECT_NE(run.summary.find("px from the recording ("), std::string::npos) << run.summary;
  ExpectEveryLine(run, "recording", kSensorHaSigmaPx, 0.1 * kSensorHaSigmaPx);
  // With the frames' estimate switched off, the config's value, said so.
  std::ofstream(dir_ / "no_frames.yaml")
      << ReadFile(DEPTHBIAS_SOURCE_DIR "/config/obstacle_detector.yaml")
      << "\nnoise: {from_frames: false}\n";
  const auto r = RunShell(Bin("obstacle_detector") + " --weights " + (dir_ / "old.yaml").string() +
                              " --config " + (dir_ / "no_frames.yaml").string() + " --out " +
                              (dir_ / "config.jsonl").string() + " " + bag_,
                          dir_);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("sigma_d 0.08 px configured"), std::string::npos) << r.out;
  std::istringstream lines(ReadFile(dir_ / "config.jsonl"));
  std::string line;
  ASSERT_TRUE(std::getline(lines, line));
  EXPECT_NE(line.find("\"disparity_noise_px\": 0.08, \"disparity_noise_from\": \"config\""),
            std::string::npos)
      << line;
}

}  // namespace
}  // namespace depthbias
