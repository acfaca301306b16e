// The obstacle detector as users run it. A simulated D455 with a disparity offset of −0.2 px
// (far targets read farther: the dangerous direction) is calibrated on the panel protocol
// (simulate → bags → panel_extract → fit_bias); then obstacle_detector runs on that unit's
// recordings of people standing from 3.5 to 15 m, ±32° off-axis, beside bushes and before a
// hedge. Every person must be found in ≥ 95 % of frames; beyond 7 m the corrected range must be
// closer to the truth than the raw one; the safe range (corrected − 2σ) may lie beyond the truth
// in no more than the 2.5 % that k = 2 allows.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

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

// The article's design, one scenario (daylight, HD, emitter on), the built-in sensor
// (σ_d = 0.08 px).
constexpr char kPanelProtocol[] = R"(protocol:
  distances_m: [4, 8, 12, 16]
  angles_deg: [0, 10, 20, 35]
  presets: [HD]
  emitters: ["on"]
  lights: [daylight]
  distance_is: range
  frames: 4
scene: {camera_height_m: 1.0, panel_center_height_m: 1.0}
)";

// Seven people (none hiding another), two bushes 0.5 m beside two of them, a hedge at 22 m.
constexpr char kObstacleProtocol[] = R"(protocol:
  presets: [HD]
  emitters: ["on"]
  lights: [daylight]
  frames: 20
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

TEST(ObstacleDetectorApp, CalibratedUnitFindsEveryPersonWithHonestSafeRanges) {
  for (const char* app : {"simulate", "panel_extract", "fit_bias", "obstacle_detector"})
    ASSERT_TRUE(fs::exists(Bin(app))) << app << " is not built";
  const fs::path d = fs::path(DEPTHBIAS_BINARY_DIR) / "detect_e2e_test";
  fs::remove_all(d);
  fs::create_directories(d);
  std::ofstream(d / "effects.yaml") << kEffects;
  std::ofstream(d / "panel.yaml") << kPanelProtocol;
  std::ofstream(d / "obstacles.yaml") << kObstacleProtocol;
  std::string err;

  // 1. Calibration: panel recordings → metrics → weights.
  ASSERT_EQ(RunApp(Bin("simulate") + " --protocol " + (d / "panel.yaml").string() +
                    " --sensor builtin --effects " + (d / "effects.yaml").string() +
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
  ASSERT_EQ(weights.groups.size(), 1u);
  ASSERT_TRUE(weights.groups[0].margin.known);
  EXPECT_NEAR(weights.groups[0].values[0], -0.2, 0.05) << "delta_px recovered from the bags";

  // 2. The same unit's obstacle recordings.
  ASSERT_EQ(RunApp(Bin("simulate") + " --protocol " + (d / "obstacles.yaml").string() +
                    " --sensor builtin --effects " + (d / "effects.yaml").string() +
                    " --seed 4 --out-dir " + (d / "obstacle_bags").string(),
                d, &err),
            0)
      << err;
  const fs::path bag = d / "obstacle_bags" / "sim_daylight_emitter-on_obstacles_HD.bag";
  ASSERT_EQ(RunApp(Bin("obstacle_detector") + " --weights " + (d / "weights.yaml").string() +
                    " --light daylight --k 2 --config " DEPTHBIAS_SOURCE_DIR
                    "/config/obstacle_detector.yaml --out " + (d / "detections.jsonl").string() +
                    " " + bag.string(),
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

  // 3. Every frame's obstacles against the truth.
  std::vector<YAML::Node> frames;
  std::istringstream lines(ReadFile(d / "detections.jsonl"));
  for (std::string line; std::getline(lines, line);) frames.push_back(YAML::Load(line));
  ASSERT_EQ(frames.size(), 20u);
  int safe_beyond = 0, matched = 0;
  for (const Truth& t : people) {
    int found = 0;
    double raw_error = 0, corrected_error = 0;
    for (const YAML::Node& f : frames) {
      YAML::Node best;  // a handle to the matched obstacle (null: none)
      double best_gap = 0.6;  // lateral distance to the truth's direction [m]
      for (const YAML::Node& o : f["obstacles"]) {
        const double gap =
            std::fabs(o["azimuth_deg"].as<double>() - t.azimuth_deg) * M_PI / 180.0 * t.range_m;
        if (gap < best_gap && std::fabs(o["range_m"].as<double>() - t.range_m) < 1.5) {
          best_gap = gap;
          best = o;
        }
      }
      if (!best) continue;
      ++found;
      ++matched;
      raw_error += best["range_m"].as<double>() - t.range_m;
      corrected_error += best["corrected_range_m"].as<double>() - t.range_m;
      safe_beyond += best["safe_range_m"].as<double>() > t.range_m;
      EXPECT_EQ(best["points"].as<int>() > 0, true);
    }
    EXPECT_GE(found, static_cast<int>(std::ceil(0.95 * frames.size())))
        << "person at " << t.range_m << " m, " << t.azimuth_deg << " deg";
    if (found == 0) continue;
    raw_error /= found;
    corrected_error /= found;
    std::printf("person %5.1f m %6.1f deg: found %d/%zu, raw %+.3f m, corrected %+.3f m\n",
                t.range_m, t.azimuth_deg, found, frames.size(), raw_error, corrected_error);
    if (t.range_m > 7.0) {
      EXPECT_LT(std::fabs(corrected_error), std::fabs(raw_error))
          << "person at " << t.range_m << " m";
    }
  }
  // k = 2: at most 2.5 % of the safe ranges beyond the truth.
  EXPECT_LE(safe_beyond, 0.025 * matched) << safe_beyond << " of " << matched;
  fs::remove_all(d / "obstacle_bags");
}

}  // namespace
}  // namespace depthbias
