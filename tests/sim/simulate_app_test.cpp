// simulate as a user runs it: the metrics-only table, clear one-line errors, and the written
// bags measured by panel_extract against the metrics-only path on every protocol cell.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "io/bag.h"
#include "io/manifest.h"
#include "io/metrics_csv.h"
#include "support/tools.h"

namespace depthbias {
namespace {

namespace fs = std::filesystem;

using test_support::Bin;
using test_support::ReadFile;
using test_support::RunShell;

fs::path Dir(const std::string& name) {
  const fs::path d = fs::path(DEPTHBIAS_BINARY_DIR) / "simulate_app_test" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void Write(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
}

// Runs a command; returns its exit status and what it wrote to stderr.
int RunCommand(const std::string& args, const fs::path& dir, std::string* err = nullptr) {
  const auto r = RunShell(args, dir);
  if (err) *err = r.err;
  return r.code;
}

const std::string kProtocol = DEPTHBIAS_SOURCE_DIR "/config/protocol_paper.yaml";

TEST(SimulateApp, MetricsOnlyGivesEveryCell) {
  const fs::path d = Dir("metrics_only");
  const std::string out = (d / "m.csv").string();
  const std::string cmd =
      Bin("simulate") + " --protocol " + kProtocol + " --metrics-only --frames 2 --out " + out;
  ASSERT_EQ(RunCommand(cmd, d), 0) << ReadFile(d / "stderr.txt");
  const auto rows = io::ReadMetricsCsv(out);
  ASSERT_EQ(rows.size(), 128u);
  for (const auto& r : rows) {
    EXPECT_TRUE(r.ok()) << r.bag << ": " << r.message;
    EXPECT_GT(r.region_px, 1000.0) << r.bag;
  }
}

TEST(SimulateApp, BadInputGivesOneClearLine) {
  const fs::path d = Dir("bad_input");
  const std::string base = Bin("simulate") + " --protocol " + kProtocol +
                           " --metrics-only --frames 1 --out " + (d / "m.csv").string();
  struct Case {
    std::string yaml;
    std::string says;
  };
  const std::vector<Case> cases = {
      {"effects: [{name: lens_flare, size: 1}]\n", "unknown effect 'lens_flare'"},
      {"effects: [{name: disparity_offset, delta_px: a lot}]\n",
       "effects[0].delta_px: expected a number"},
      {"effects: [{name: edge_mixing, width: 3}]\n", "unknown parameter 'width'"},
      {"effects: [{name: invalidation_gain, gain: -2}]\n", "outside"},
  };
  for (const auto& c : cases) {
    const fs::path effects = d / "effects.yaml";
    Write(effects, c.yaml);
    std::string err;
    EXPECT_EQ(RunCommand(base + " --effects " + effects.string(), d, &err), 2) << c.yaml;
    EXPECT_NE(err.find(effects.string()), std::string::npos) << err;
    EXPECT_NE(err.find(c.says), std::string::npos) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_FALSE(fs::exists(d / "m.csv"));
  }
  std::string err;
  EXPECT_EQ(RunCommand(base + " --effects " + (d / "missing.yaml").string(), d, &err), 2);
  EXPECT_NE(err.find("missing.yaml"), std::string::npos) << err;
  const std::string bad_frames =
      Bin("simulate") + " --protocol " + kProtocol + " --frames zero --metrics-only";
  EXPECT_EQ(RunCommand(bad_frames, d, &err), 2);
  EXPECT_NE(err.find("--frames"), std::string::npos) << err;
  const fs::path protocol = d / "protocol.yaml";
  Write(protocol, "protocol: {distance_is: slant}\n");
  const std::string bad_protocol = Bin("simulate") + " --protocol " + protocol.string() +
                                   " --metrics-only --out " + (d / "m.csv").string();
  EXPECT_EQ(RunCommand(bad_protocol, d, &err), 2);
  EXPECT_NE(err.find("protocol.yaml: protocol.distance_is"), std::string::npos) << err;
  // An output that is also an input is refused, and the input left as it was.
  const fs::path kept = d / "kept.yaml";
  Write(kept, "protocol: {frames: 2}\n");
  EXPECT_EQ(RunCommand(Bin("simulate") + " --protocol " + kept.string() + " --metrics-only --out " +
                           kept.string(),
                       d, &err),
            2);
  EXPECT_NE(err.find("is also an input"), std::string::npos) << err;
  EXPECT_EQ(ReadFile(kept), "protocol: {frames: 2}\n");
  // A file that is not YAML at all is named in one short line.
  const fs::path csv = d / "table.csv";
  Write(csv, std::string("bag,light\n") + std::string(5000, 'x') + ",daylight\n");
  EXPECT_EQ(RunCommand(Bin("simulate") + " --protocol " + csv.string() + " --metrics-only --out " +
                           (d / "m.csv").string(),
                       d, &err),
            2);
  EXPECT_NE(err.find("table.csv"), std::string::npos) << err;
  EXPECT_LT(err.size(), 300u) << err;
}

// Recordings are simulated several at a time, and a recording's frames on several threads when
// there are more threads than recordings: the bags must not depend on either.
TEST(SimulateApp, BagsDoNotDependOnThreads) {
  const fs::path d = Dir("threads");
  const fs::path protocol = d / "protocol.yaml";
  Write(protocol,
        "protocol: {distances_m: [4, 12], angles_deg: [0, 20], lights: [daylight], "
        "presets: [HD], emitters: [\"on\"], frames: 3}\n");
  std::map<int, std::map<std::string, std::string>> bags;  // threads → bag name → bytes
  for (int threads : {1, 2, 8}) {
    const fs::path out = d / ("t" + std::to_string(threads));
    const std::string sim = Bin("simulate") + " --protocol " + protocol.string() +
                            " --sensor builtin --threads " + std::to_string(threads) +
                            " --out-dir " + out.string();
    ASSERT_EQ(RunCommand(sim, d), 0) << ReadFile(d / "stderr.txt");
    for (const auto& e : fs::directory_iterator(out))
      bags[threads][e.path().filename().string()] = ReadFile(e.path());
  }
  ASSERT_EQ(bags[1].size(), 5u);  // 4 bags and the manifest
  for (const auto& [name, bytes] : bags[1]) {
    EXPECT_GT(bytes.size(), 0u) << name;
    EXPECT_TRUE(bags[2][name] == bytes) << name << " differs with 2 threads";
    EXPECT_TRUE(bags[8][name] == bytes) << name << " differs with 8 threads";
  }
}

// The simulated camera takes a real recording's intrinsics, depth units and baseline (the fixture
// was written by librealsense's recorder: 64×48, fx 40, Stereo_Baseline 95.07 mm, distorted).
TEST(SimulateApp, SensorFromRecordingTakesItsCamera) {
  const fs::path d = Dir("sensor_from");
  const fs::path protocol = d / "protocol.yaml";
  Write(protocol,
        "protocol: {distances_m: [4], angles_deg: [0], lights: [daylight], presets: [HA], "
        "emitters: [\"off\"], frames: 2}\n");
  const std::string recording = DEPTHBIAS_TEST_DATA "/bags/d455_depth_1mm.bag";
  std::string err;
  ASSERT_EQ(RunCommand(Bin("simulate") + " --protocol " + protocol.string() +
                           " --sensor builtin --sensor-from " + recording + " --out-dir " +
                           (d / "bags").string(),
                       d, &err),
            0)
      << err;
  EXPECT_NE(err.find("distortion coefficients ignored"), std::string::npos) << err;
  std::vector<fs::path> bags;
  for (const auto& e : fs::directory_iterator(d / "bags"))
    if (e.path().extension() == ".bag") bags.push_back(e.path());
  ASSERT_EQ(bags.size(), 1u);
  io::BagReader reader(bags[0].string());
  const io::BagInfo& info = reader.info();
  EXPECT_EQ(info.depth_intrinsics.width, 64);
  EXPECT_EQ(info.depth_intrinsics.height, 48);
  EXPECT_NEAR(info.depth_intrinsics.fx, 40.0, 1e-6);
  EXPECT_NEAR(info.depth_intrinsics.fy, 40.12, 1e-5);
  EXPECT_NEAR(info.depth_intrinsics.ppx, 31.63, 1e-5);
  for (double c : info.depth_intrinsics.coeffs) EXPECT_EQ(c, 0.0);
  EXPECT_NEAR(info.depth_units_m, 0.001, 1e-9);
  EXPECT_NEAR(info.options.at("Stereo_Baseline"), 95.07, 1e-3);
  records::DepthFrame frame;
  ASSERT_TRUE(reader.Next(&frame));
  EXPECT_EQ(frame.counts.size(), 64u * 48u);

  const fs::path not_a_bag = d / "notes.bag";
  Write(not_a_bag, "not a bag\n");
  ASSERT_EQ(RunCommand(Bin("simulate") + " --protocol " + protocol.string() + " --sensor-from " +
                           not_a_bag.string() + " --out-dir " + (d / "bags2").string(),
                       d, &err),
            2);
  EXPECT_NE(err.find("notes.bag"), std::string::npos) << err;
  EXPECT_EQ(err.find('\n'), err.size() - 1) << err;  // one line
  EXPECT_FALSE(fs::exists(d / "bags2"));

  // A recording at 100 µm units: the simulated range is the camera's at those units (6.55 m).
  const std::string fine = DEPTHBIAS_TEST_DATA "/bags/d455_depth_100um_lz4.bag";
  ASSERT_EQ(RunCommand(Bin("simulate") + " --protocol " + protocol.string() +
                           " --sensor builtin --sensor-from " + fine + " --out-dir " +
                           (d / "bags3").string(),
                       d, &err),
            0)
      << err;
  const io::Manifest manifest = io::ReadManifest((d / "bags3" / "manifest.csv").string());
  ASSERT_EQ(manifest.rows().size(), 1u);
  io::BagReader fine_reader((d / "bags3" / manifest.rows()[0].bag).string());
  EXPECT_NEAR(fine_reader.info().depth_units_m, 0.0001, 1e-9);
  ASSERT_TRUE(fine_reader.Next(&frame));
  int valid = 0;
  for (std::uint16_t c : frame.counts) {
    EXPECT_LE(c * 0.0001, 6.5535 + 1e-9);
    valid += c != 0;
  }
  EXPECT_GT(valid, 0);  // the panel at 4 m is in range
}

// The panel's temporal disparity noise (sigma_d_px, the estimator the obstacle detector uses at
// its obstacles: camera/disparity_noise.h) on simulated recordings of the calibrated sensor
// (config/sensor_calibrated.yaml, daylight: HA σ_d 0.0698 px, HD 0.15 px): panel_extract on the
// bags recovers each preset's σ_d within 10 % at every distance and angle, the metrics-only path
// fills the same column, and fit_bias writes the unit's σ_d per group from it.
TEST(SimulateApp, PanelExtractMeasuresTheSensorsDisparityNoise) {
  const std::map<std::string, double> sensor_sigma_px = {{"HA", 0.06983629732}, {"HD", 0.15}};
  const fs::path d = Dir("sigma_d");
  const fs::path protocol = d / "protocol.yaml";
  Write(protocol,
        "protocol: {distances_m: [4, 8, 12, 16], angles_deg: [0, 20], lights: [daylight], "
        "presets: [HA, HD], emitters: [\"on\"], frames: 10, distance_is: range}\n"
        "scene: {camera_height_m: 1.0, panel_center_height_m: 1.0}\n");
  const std::string sim = Bin("simulate") + " --protocol " + protocol.string() + " --sensor " +
                          DEPTHBIAS_SOURCE_DIR "/config/sensor_calibrated.yaml --seed 5";
  std::string err;
  ASSERT_EQ(RunCommand(sim + " --out-dir " + (d / "bags").string(), d, &err), 0) << err;
  ASSERT_EQ(RunCommand(Bin("panel_extract") + " --jobs 2 --quiet --manifest " +
                           (d / "bags" / "manifest.csv").string() + " --out " +
                           (d / "extract.csv").string() + " " + (d / "bags").string(),
                       d, &err),
            0)
      << err;
  fs::remove_all(d / "bags");
  ASSERT_EQ(RunCommand(sim + " --metrics-only --out " + (d / "sim.csv").string(), d, &err), 0)
      << err;
  for (const char* table : {"extract.csv", "sim.csv"}) {
    const auto rows = io::ReadMetricsCsv((d / table).string());
    ASSERT_EQ(rows.size(), 16u) << table;
    for (const auto& r : rows) {
      ASSERT_TRUE(r.ok()) << table << " " << r.bag << ": " << r.message;
      const double truth = sensor_sigma_px.at(r.preset);
      EXPECT_NEAR(r.sigma_d_px, truth, 0.1 * truth) << table << " " << r.bag;
      std::printf("%-11s %-4s %4g m %4g deg  sigma_d_px %.4f (sensor %.4f, %+.1f %%)\n", table,
                  r.preset.c_str(), r.distance_m, r.angle_deg, r.sigma_d_px, truth,
                  100 * (r.sigma_d_px / truth - 1));
    }
  }
  // fit_bias: the median of each group's recordings, with their number.
  ASSERT_EQ(RunCommand(Bin("fit_bias") + " --cv none --in " + (d / "extract.csv").string() +
                           " --out " + (d / "w.yaml").string(),
                       d, &err),
            0)
      << err;
  const std::string weights = ReadFile(d / "w.yaml");
  for (const auto& [preset, truth] : sensor_sigma_px) {
    const size_t group = weights.find("preset: " + preset);
    ASSERT_NE(group, std::string::npos) << weights;
    const size_t at = weights.find("disparity_noise: {sigma_px: ", group);
    ASSERT_NE(at, std::string::npos) << weights;
    EXPECT_NEAR(std::stod(weights.substr(at + 28)), truth, 0.1 * truth) << preset;
    EXPECT_NE(weights.find("recordings: 8}", at), std::string::npos) << weights;
  }
}

}  // namespace
}  // namespace depthbias
