// The obstacle detector as users run it. A simulated D455 (the calibrated sensor,
// config/sensor_calibrated.yaml: High Accuracy σ_d = 0.07 px with 71 % holes, High Density
// σ_d = 0.15 px) with a disparity offset of −0.2 px (far targets read farther: the dangerous
// direction) is calibrated on the panel protocol in both presets (simulate → bags →
// panel_extract → fit_bias, which writes each preset's σ_d from the panel recordings); then
// obstacle_detector runs on that unit's recordings of people standing from 3.5 to 15 m, ±32°
// off-axis, beside bushes and before a hedge, 60 frames per preset. Per preset and per range, never pooled: every person is found in ≥ 95 % of frames;
// beyond 7 m the corrected range is closer to the truth than the raw one; the safe range
// (min(raw, corrected − 2σ)) lies beyond the truth in at most 2.5 % of the frames (1 of 60).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "io/csv.h"
#include "io/weights_yaml.h"
#include "support/tools.h"

namespace depthbias {
namespace {

// P(X >= k) for X ~ Binomial(n, p).
double BinomialTail(int k, int n, double p) {
  double below = 0, term = std::pow(1 - p, n);  // P(X = 0)
  for (int i = 0; i < k && i <= n; ++i) {
    below += term;
    term *= (n - i) / (i + 1.0) * p / (1 - p);
  }
  return std::max(0.0, 1 - below);
}

namespace fs = std::filesystem;

using test_support::Bin;
using test_support::ReadFile;
using test_support::RunShell;

// Runs a command in dir; its exit status (stderr in *err).
int RunApp(const std::string& args, const fs::path& dir, std::string* err) {
  const auto r = RunShell(args, dir);
  *err = r.err + r.out;
  return r.code;
}

constexpr char kEffects[] = "effects:\n  - {name: disparity_offset, delta_px: -0.2}\n";

// The article's design, daylight, emitter on, both presets.
constexpr char kPanelProtocol[] = R"(protocol:
  distances_m: [4, 8, 12, 16]
  angles_deg: [0, 10, 20, 35]
  presets: [HA, HD]
  emitters: ["on"]
  lights: [daylight]
  distance_is: range
  frames: 10
scene: {camera_height_m: 1.0, panel_center_height_m: 1.0}
)";

// Seven people (none hiding another), two bushes 0.5 m beside two of them, a hedge at 22 m.
constexpr char kObstacleProtocol[] = R"(protocol:
  presets: [HA, HD]
  emitters: ["on"]
  lights: [daylight]
  frames: 60
scene:
  camera_height_m: 1.0
  panel: off
  obstacles:
    - {kind: person, range_m: 3.5, azimuth_deg: -32}
    - {kind: person, range_m: 13, azimuth_deg: -21}
    - {kind: person, range_m: 7, azimuth_deg: -11}
    - {kind: person, range_m: 11, azimuth_deg: 0}
    - {kind: person, range_m: 5, azimuth_deg: 11}
    - {kind: person, range_m: 15, azimuth_deg: 21}
    - {kind: person, range_m: 9, azimuth_deg: 32}
    - {kind: bush, range_m: 13, azimuth_deg: -15.5}
    - {kind: bush, range_m: 9, azimuth_deg: 40}
  hedge: {distance_m: 22, height_m: 2.0}
)";

struct Truth {
  std::string kind;
  double range_m, azimuth_deg;
};

const std::string kSensor = DEPTHBIAS_SOURCE_DIR "/config/sensor_calibrated.yaml";

TEST(ObstacleDetectorApp, CalibratedUnitCoveragePerRangeAndPreset) {
  for (const char* app : {"simulate", "panel_extract", "fit_bias", "obstacle_detector"})
    ASSERT_TRUE(fs::exists(Bin(app))) << app << " is not built";
  const fs::path d = fs::path(DEPTHBIAS_BINARY_DIR) / "detect_e2e_test";
  fs::remove_all(d);
  fs::create_directories(d);
  std::ofstream(d / "effects.yaml") << kEffects;
  std::ofstream(d / "panel.yaml") << kPanelProtocol;
  std::ofstream(d / "obstacles.yaml") << kObstacleProtocol;
  std::string err;

  // 1. Calibration: panel recordings → metrics → weights, one group per preset.
  ASSERT_EQ(RunApp(Bin("simulate") + " --protocol " + (d / "panel.yaml").string() +
                    " --sensor " + kSensor + " --effects " + (d / "effects.yaml").string() +
                    " --seed 3 --out-dir " + (d / "panel_bags").string(),
                d, &err),
            0)
      << err;
  ASSERT_EQ(RunApp(Bin("panel_extract") + " --jobs 2 --quiet --manifest " +
                    (d / "panel_bags" / "manifest.csv").string() + " --out " +
                    (d / "metrics.csv").string() + " " + (d / "panel_bags").string(),
                d, &err),
            0)
      << err;
  fs::remove_all(d / "panel_bags");
  ASSERT_EQ(RunApp(Bin("fit_bias") + " --in " + (d / "metrics.csv").string() + " --out " +
                    (d / "weights.yaml").string(),
                d, &err),
            0)
      << err;
  const auto weights = io::ReadWeightsYaml((d / "weights.yaml").string());
  ASSERT_EQ(weights.groups.size(), 2u);
  for (const auto& g : weights.groups) {
    ASSERT_TRUE(g.margin.known) << g.preset;
    EXPECT_NEAR(g.values[0], -0.2, 0.05) << g.preset << ": delta_px recovered from the bags";
    ASSERT_TRUE(g.disparity_noise.known) << g.preset << ": σ_d of the panel recordings";
    EXPECT_EQ(g.disparity_noise.recordings, 16) << g.preset;
    std::printf("weights %s/%s: sigma_d %.4f px (median of %d recordings)\n", g.light.c_str(),
                g.preset.c_str(), g.disparity_noise.sigma_px, g.disparity_noise.recordings);
  }

  // 2. The same unit's obstacle recordings, one per preset.
  ASSERT_EQ(RunApp(Bin("simulate") + " --protocol " + (d / "obstacles.yaml").string() +
                    " --sensor " + kSensor + " --effects " + (d / "effects.yaml").string() +
                    " --seed 4 --out-dir " + (d / "obstacle_bags").string(),
                d, &err),
            0)
      << err;
  const io::CsvTable table = io::ReadCsv((d / "obstacle_bags" / "obstacles.csv").string());
  std::vector<Truth> people;
  for (size_t r = 0; r < table.rows.size(); ++r) {
    const std::string kind = table.Cell(r, table.RequireColumn("kind"));
    if (kind == "person")
      people.push_back({kind, table.Number(r, table.RequireColumn("range_m")),
                        table.Number(r, table.RequireColumn("azimuth_deg"))});
  }
  ASSERT_EQ(people.size(), 7u);
  std::sort(people.begin(), people.end(),
            [](const Truth& a, const Truth& b) { return a.range_m < b.range_m; });

  std::printf("| preset | person at | found | raw − truth | corrected − truth | σ | "
              "safe range beyond truth |\n|---|---|---|---|---|---|---|\n");
  for (const std::string preset : {"HA", "HD"}) {
    const fs::path bag =
        d / "obstacle_bags" / ("sim_daylight_emitter-on_obstacles_" + preset + ".bag");
    const fs::path out = d / ("detections_" + preset + ".jsonl");
    ASSERT_EQ(RunApp(Bin("obstacle_detector") + " --weights " + (d / "weights.yaml").string() +
                      " --light daylight --k 2 --config " DEPTHBIAS_SOURCE_DIR
                      "/config/obstacle_detector.yaml --out " + out.string() + " " +
                      bag.string(),
                  d, &err),
              0)
        << err;
    EXPECT_NE(err.find("daylight/" + preset), std::string::npos) << err;
    // σ_d: the unit's, from its weights (fit_bias: the median of the 16 panel recordings of
    // this preset, measured by panel_extract), not from this recording's frames.
    EXPECT_NE(err.find("px from the weights (daylight/" + preset + ", median of 16 recordings)"),
              std::string::npos)
        << err;
    double sensor_sigma_px = 0;  // the simulated unit's σ_d in this preset
    for (const YAML::Node& sc : YAML::LoadFile(kSensor)["sensor"]["scenarios"])
      if (sc["light"].as<std::string>() == "daylight" && sc["preset"].as<std::string>() == preset)
        sensor_sigma_px = sc["sigma_d_px"].as<double>();
    ASSERT_GT(sensor_sigma_px, 0.0) << preset;

    // 3. Every frame's obstacles against the truth, per range.
    std::vector<YAML::Node> frames;
    std::istringstream lines(ReadFile(out));
    for (std::string line; std::getline(lines, line);) frames.push_back(YAML::Load(line));
    ASSERT_EQ(frames.size(), 60u);
    for (const Truth& t : people) {
      int found = 0, safe_beyond = 0;
      double raw_error = 0, corrected_error = 0, sigma = 0;
      for (const YAML::Node& f : frames) {
        EXPECT_EQ(f["status"].as<std::string>(), "ok");
        // The margin's σ_d is this preset's (the unit's weights), not one global 0.08 px.
        EXPECT_NEAR(f["disparity_noise_px"].as<double>(), sensor_sigma_px, 0.1 * sensor_sigma_px)
            << preset;
        EXPECT_EQ(f["disparity_noise_from"].as<std::string>(), "weights") << preset;
        YAML::Node best;  // a handle to the matched obstacle (null: none)
        double best_gap = 0.6;  // lateral distance to the truth's direction [m]
        for (const YAML::Node& o : f["obstacles"]) {
          const double gap = std::fabs(o["azimuth_deg"].as<double>() - t.azimuth_deg) * M_PI /
                             180.0 * t.range_m;
          if (gap < best_gap && std::fabs(o["range_m"].as<double>() - t.range_m) < 1.5) {
            best_gap = gap;
            best = o;
          }
        }
        if (!best) continue;
        ++found;
        raw_error += best["range_m"].as<double>() - t.range_m;
        corrected_error += best["corrected_range_m"].as<double>() - t.range_m;
        sigma += best["std_m"].as<double>();
        safe_beyond += best["safe_range_m"].as<double>() > t.range_m;
        EXPECT_LE(best["safe_range_m"].as<double>(), best["range_m"].as<double>());
      }
      const std::string where = preset + ", person at " + std::to_string(t.range_m) + " m";
      EXPECT_GE(found, static_cast<int>(std::ceil(0.95 * frames.size()))) << where;
      if (found == 0) continue;
      std::printf("| %s | %g m, %g° | %d/%zu | %+.3f m | %+.3f m | %.3f m | %d/%d |\n",
                  preset.c_str(), t.range_m, t.azimuth_deg, found, frames.size(),
                  raw_error / found, corrected_error / found, sigma / found, safe_beyond, found);
      if (t.range_m > 7.0) {
        EXPECT_LT(std::fabs(corrected_error), std::fabs(raw_error)) << where;
      }
      // k = 2 promises that a safe range lies beyond the truth in at most 2.28 % of readings
      // (the normal tail). With 60 frames a range's count is binomial: even a σ of exactly the
      // right size shows 2 or more misses at a range in 40 % of runs, so "at most 1 of 60" would
      // fail by chance. The check is that the count is credible under the promise: its tail
      // probability P(X >= misses | n, 2.28 %) stays above 0.001 (7 or fewer of 60 misses).
      const double p_promise = BinomialTail(safe_beyond, found, 0.0228);
      EXPECT_GE(p_promise, 0.001) << where << ": " << safe_beyond << " of " << found
                                  << " beyond the truth, p " << p_promise;
    }
  }
  fs::remove_all(d / "obstacle_bags");
}

}  // namespace
}  // namespace depthbias
