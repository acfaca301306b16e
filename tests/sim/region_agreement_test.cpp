// One region, one definition on both sides of the comparison: the article's protocol simulated at
// 6 frames both ways, bags through panel_extract against the metrics-only path, compared column by
// column on all 128 cells. The two paths decide the panel's pixels from the pooled frames by the
// same function (metrics/panel_pixels.h) and measure them by the same kernel; what remains is the
// detected rectangle against the true one, placed to within a pixel: the region may gain or lose
// a row and a column. Each column is held to that quantization:
//  - frames: equal;
//  - median, range, mean: one disparity step (1/32 px) in depth at Z, Z²/(32·f·B), + 1 mm;
//  - region_px: one row and one column of the region, each a pixel longer, 2·side + 2 pixels
//    (side = √region_px);
//  - hole rate and valid %: that many pixels' worth of the region, 100·(2·side + 2)/px;
//  - width, height: a column or row on each side, two pixel footprints 2·Z/f;
//  - azimuth, elevation: one pixel's angle 1/f rad, + 0.01° for the plane's noise;
//  - plane_std, subpixel_rms, temporal_std, sigma_d: statistics of the samples, held relatively
//    to three times the share of the region that row and column make, 3·(2·side + 2)/px, + 1 %;
//  - normal tilt: 1.5 standard errors of the inverse-depth plane's slope, + 0.1°.
// The table printed gives, per column, the cells beyond their tolerance and the largest
// difference in units of it. The manifest's truth (true_hole_rate_pct) is the metrics-only hole
// rate of the same draws.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "io/manifest.h"
#include "io/metrics_csv.h"
#include "support/tools.h"

namespace depthbias {
namespace {

namespace fs = std::filesystem;

using test_support::Bin;
using test_support::ReadFile;
using test_support::RunShell;

constexpr double kFocalPx = 640.0;  // the D455's depth fx at 1280×720 (config/sensor_*.yaml)
constexpr double kBaselineM = 0.095;

struct Column {
  std::string name;
  std::function<double(const records::PanelMetrics&)> value;
  // Tolerance at a cell, from the metrics-only row s.
  std::function<double(const records::PanelMetrics&)> tolerance;
  bool relative = false;  // compare e / s − 1 rather than e − s
};

double StepM(const records::PanelMetrics& s) {
  return s.median_m * s.median_m / (kFocalPx * kBaselineM) / 32.0;
}
// Pixels of one row and one column of the region, each a pixel longer (its sides from its pixel
// count).
double EdgePx(const records::PanelMetrics& s) { return 2.0 * std::sqrt(s.region_px) + 2.0; }

std::vector<Column> Columns() {
  using M = records::PanelMetrics;
  const double deg_per_px = 180.0 / M_PI / kFocalPx;
  auto share = [](const M& s) { return EdgePx(s) / s.region_px; };
  return {
      {"frames", [](const M& m) { return m.frames; }, [](const M&) { return 0.0; }},
      {"median_m", [](const M& m) { return m.median_m; },
       [](const M& s) { return StepM(s) + 0.001; }},
      {"mean_m", [](const M& m) { return m.mean_m; },
       [](const M& s) { return StepM(s) + 0.001; }},
      {"range_m", [](const M& m) { return m.range_m; },
       [](const M& s) { return StepM(s) * s.range_m / s.median_m + 0.001; }},
      {"region_px", [](const M& m) { return m.region_px; }, [](const M& s) { return EdgePx(s); }},
      {"hole_rate_pct", [](const M& m) { return m.hole_rate_pct; },
       [=](const M& s) { return 100.0 * share(s); }},
      {"valid_pct", [](const M& m) { return m.valid_pct; },
       [=](const M& s) { return 100.0 * share(s); }},
      {"panel_width_m", [](const M& m) { return m.panel_width_m; },
       [](const M& s) { return 2 * s.median_m / kFocalPx; }},
      {"panel_height_m", [](const M& m) { return m.panel_height_m; },
       [](const M& s) { return 2 * s.median_m / kFocalPx; }},
      {"azimuth_deg", [](const M& m) { return m.azimuth_deg; },
       [=](const M&) { return deg_per_px + 0.01; }},
      {"elevation_deg", [](const M& m) { return m.elevation_deg; },
       [=](const M&) { return deg_per_px + 0.01; }},
      {"plane_std_m", [](const M& m) { return m.plane_std_m; },
       [=](const M& s) { return 3 * share(s) + 0.01; }, true},
      {"subpixel_rms_px", [](const M& m) { return m.subpixel_rms_px; },
       [=](const M& s) { return 3 * share(s) + 0.01; }, true},
      {"temporal_std_m", [](const M& m) { return m.temporal_std_m; },
       [=](const M& s) { return 3 * share(s) + 0.01; }, true},
      {"sigma_d_px", [](const M& m) { return m.sigma_d_px; },
       [=](const M& s) { return 3 * share(s) + 0.01; }, true},
      {"normal_tilt_deg", [](const M& m) { return m.normal_tilt_deg; },
       [](const M& s) {
         // Standard error of the inverse-depth plane's slope: Z·σ_d·√12 / (B·side·√n).
         const double side = std::sqrt(s.region_px);
         const double n = std::max(1.0, s.valid_pct / 100.0 * s.region_px * s.frames);
         return 0.1 + 1.5 * s.median_m * s.subpixel_rms_px * std::sqrt(12.0) /
                          (kBaselineM * side * std::sqrt(n)) * 180.0 / M_PI;
       }},
  };
}

using Pairs = std::vector<std::pair<records::PanelMetrics, records::PanelMetrics>>;

// One light and preset simulated both ways at seed 11 and 6 frames (with the effects YAML
// `effects`, none when empty), bags through panel_extract: the (extract, metrics-only) pairs.
// With `missed`, recordings where panel_extract finds no panel are counted there and left out;
// without, every recording must give one.
void RunBothWays(const fs::path& d, const std::string& light, const std::string& preset,
                 const std::string& effects, Pairs* pairs, int* missed = nullptr) {
  const fs::path sensor = DEPTHBIAS_SOURCE_DIR "/config/sensor_calibrated.yaml";
  const fs::path run = d / (light + "_" + preset);
  fs::create_directories(run);
  const fs::path protocol = run / "protocol.yaml";
  std::ofstream(protocol) << "protocol: {lights: [" << light << "], presets: [" << preset
                          << "], frames: 6}\n";
  std::string sim = Bin("simulate") + " --protocol " + protocol.string() + " --sensor " +
                    sensor.string() + " --seed 11";
  if (!effects.empty()) {
    std::ofstream(run / "effects.yaml") << effects;
    sim += " --effects " + (run / "effects.yaml").string();
  }
  ASSERT_EQ(RunShell(sim + " --out-dir " + (run / "bags").string(), run).code, 0)
      << ReadFile(run / "stderr.txt");
  ASSERT_EQ(RunShell(sim + " --metrics-only --out " + (run / "sim.csv").string(), run).code, 0)
      << ReadFile(run / "stderr.txt");
  const std::string extract = Bin("panel_extract") + " --jobs 2 --manifest " +
                              (run / "bags" / "manifest.csv").string() + " --out " +
                              (run / "extract.csv").string() + " " + (run / "bags").string();
  const int code = RunShell(extract, run).code;
  ASSERT_TRUE(code == 0 || (missed && code == 1)) << ReadFile(run / "stderr.txt");
  std::map<std::string, records::PanelMetrics> extracted;
  for (const auto& r : io::ReadMetricsCsv((run / "extract.csv").string())) extracted[r.bag] = r;
  const auto simulated = io::ReadMetricsCsv((run / "sim.csv").string());
  ASSERT_EQ(simulated.size(), 32u);
  const io::Manifest manifest = io::ReadManifest((run / "bags" / "manifest.csv").string());
  for (const auto& s : simulated) {
    const io::ManifestRow* row = manifest.Find((run / "bags" / s.bag).string());
    ASSERT_NE(row, nullptr) << s.bag;
    EXPECT_NEAR(std::stod(row->extras.at("true_hole_rate_pct")), s.hole_rate_pct, 0.001);
    ASSERT_TRUE(extracted.count(s.bag)) << s.bag;
    if (missed && extracted[s.bag].status == "no_panel") {
      ++*missed;
      continue;
    }
    ASSERT_TRUE(extracted[s.bag].ok()) << s.bag << ": " << extracted[s.bag].message;
    ASSERT_TRUE(s.ok()) << s.bag << ": " << s.message;
    pairs->emplace_back(extracted[s.bag], s);
  }
  fs::remove_all(run / "bags");
}

// Prints the table of the columns (cells beyond tolerance, the largest difference in units of
// it); returns the cells with a column beyond its tolerance. A column in `loose` is printed but
// not held to its tolerance.
int CellsBeyond(const Pairs& pairs, const std::vector<std::string>& loose = {}) {
  std::printf("%-16s %8s %12s %12s %14s  %s\n", "column", "beyond", "max |diff|", "(tol there)",
              "max diff/tol", "worst cell");
  int cells_differing = 0;
  std::vector<bool> differs(pairs.size(), false);
  for (const Column& c : Columns()) {
    const bool held = std::find(loose.begin(), loose.end(), c.name) == loose.end();
    int beyond = 0;
    double worst = 0, worst_diff = 0, worst_tol = 0, max_abs = 0;
    std::string worst_bag;
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const auto& [e, s] = pairs[k];
      const double diff = c.relative ? c.value(e) / c.value(s) - 1.0 : c.value(e) - c.value(s);
      const double tol = c.tolerance(s);
      max_abs = std::max(max_abs, std::fabs(diff));
      const double ratio = tol > 0 ? std::fabs(diff) / tol : (diff == 0 ? 0.0 : INFINITY);
      if (ratio > 1.0 && held) {
        ++beyond;
        differs[k] = true;
        EXPECT_LE(std::fabs(diff), tol) << c.name << " " << s.bag << ": extract " << c.value(e)
                                        << ", metrics-only " << c.value(s);
      }
      if (ratio > worst || worst_bag.empty()) {
        worst = ratio;
        worst_diff = diff;
        worst_tol = tol;
        worst_bag = s.bag;
      }
    }
    std::printf("%-16s %8d %12.4g %12.4g %14.2f  %s (%+.4g)%s\n", c.name.c_str(), beyond, max_abs,
                worst_tol, worst, worst_bag.c_str(), worst_diff, c.relative ? " relative" : "");
  }
  for (bool b : differs) cells_differing += b;
  std::printf("cells with a column beyond its tolerance: %d of %zu\n", cells_differing,
              pairs.size());
  return cells_differing;
}

TEST(RegionAgreement, PanelExtractOnBagsAndMetricsOnlyAgreeWithinQuantization) {
  if (!fs::exists(Bin("panel_extract"))) GTEST_FAIL() << "panel_extract is not built";
  const fs::path d = fs::path(DEPTHBIAS_BINARY_DIR) / "region_agreement_test";
  fs::remove_all(d);
  fs::create_directories(d);
  Pairs pairs;
  for (const std::string light : {"daylight", "sunset"})
    for (const std::string preset : {"HA", "HD"}) {
      RunBothWays(d, light, preset, "", &pairs);
      if (HasFatalFailure()) return;
    }
  ASSERT_EQ(pairs.size(), 128u);
  EXPECT_EQ(CellsBeyond(pairs), 0);
}

// panel_extract lays the panel's known size on the plane it measures: under a range error its
// region is not the panel's footprint (smaller when over-read, the background around the panel
// taken in and then left out when under-read), and the metrics-only path draws the same one.
// With the true footprint as the region, every one of these 63 cells had its region size beyond
// its quantization, and 26 of the 31 over-read ones their width. Two columns get twice their
// quantization: region_px (the window laid on an under-read plane at 35° may take in a column
// more than the simulated one). The region's direction, azimuth and elevation, gets three
// pixels: an over-read panel looks larger than the window, which panel_extract may place
// anywhere in it (7 % of 40 px at 16 m).
TEST(RegionAgreement, UnderARangeErrorTheRegionIsPanelExtractsWindow) {
  if (!fs::exists(Bin("panel_extract"))) GTEST_FAIL() << "panel_extract is not built";
  for (const double delta : {-0.25, 0.25}) {
    const fs::path d = fs::path(DEPTHBIAS_BINARY_DIR) /
                       ("region_agreement_offset_" + std::string(delta < 0 ? "far" : "near"));
    fs::remove_all(d);
    fs::create_directories(d);
    Pairs pairs;
    int missed = 0;
    RunBothWays(d, "daylight", "HA",
                "effects:\n  - {name: disparity_offset, delta_px: " + std::to_string(delta) +
                    "}\n",
                &pairs, &missed);
    if (HasFatalFailure()) return;
    // The panel read 7 % far at 16 m is not always found (1 of 32 here): the comparison needs
    // the others.
    EXPECT_LE(missed, 2) << delta;
    std::printf("disparity offset %+.2f px\n", delta);
    EXPECT_EQ(CellsBeyond(pairs, {"region_px", "azimuth_deg", "elevation_deg"}), 0) << delta;
    const double three_px_deg = 3 * 180.0 / M_PI / kFocalPx;
    for (const auto& [e, s] : pairs) {
      EXPECT_NEAR(e.region_px, s.region_px, 2 * EdgePx(s)) << s.bag << " " << delta;
      EXPECT_NEAR(e.azimuth_deg, s.azimuth_deg, three_px_deg) << s.bag << " " << delta;
      EXPECT_NEAR(e.elevation_deg, s.elevation_deg, three_px_deg) << s.bag << " " << delta;
    }
  }
}

}  // namespace
}  // namespace depthbias
