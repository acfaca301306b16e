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

TEST(RegionAgreement, PanelExtractOnBagsAndMetricsOnlyAgreeWithinQuantization) {
  if (!fs::exists(Bin("panel_extract"))) GTEST_FAIL() << "panel_extract is not built";
  const fs::path d = fs::path(DEPTHBIAS_BINARY_DIR) / "region_agreement_test";
  fs::remove_all(d);
  fs::create_directories(d);
  const fs::path sensor = DEPTHBIAS_SOURCE_DIR "/config/sensor_calibrated.yaml";
  std::vector<std::pair<records::PanelMetrics, records::PanelMetrics>> pairs;  // (extract, sim)
  for (const std::string light : {"daylight", "sunset"}) {
    for (const std::string preset : {"HA", "HD"}) {
      const fs::path run = d / (light + "_" + preset);
      fs::create_directories(run);
      const fs::path protocol = run / "protocol.yaml";
      std::ofstream(protocol) << "protocol: {lights: [" << light << "], presets: [" << preset
                              << "], frames: 6}\n";
      const std::string sim = Bin("simulate") + " --protocol " + protocol.string() +
                              " --sensor " + sensor.string() + " --seed 11";
      ASSERT_EQ(RunShell(sim + " --out-dir " + (run / "bags").string(), run).code, 0)
          << ReadFile(run / "stderr.txt");
      ASSERT_EQ(RunShell(sim + " --metrics-only --out " + (run / "sim.csv").string(), run).code,
                0)
          << ReadFile(run / "stderr.txt");
      const std::string extract = Bin("panel_extract") + " --jobs 2 --manifest " +
                                  (run / "bags" / "manifest.csv").string() + " --out " +
                                  (run / "extract.csv").string() + " " + (run / "bags").string();
      ASSERT_EQ(RunShell(extract, run).code, 0) << ReadFile(run / "stderr.txt");
      std::map<std::string, records::PanelMetrics> extracted;
      for (const auto& r : io::ReadMetricsCsv((run / "extract.csv").string()))
        extracted[r.bag] = r;
      const auto simulated = io::ReadMetricsCsv((run / "sim.csv").string());
      ASSERT_EQ(simulated.size(), 32u);
      const io::Manifest manifest = io::ReadManifest((run / "bags" / "manifest.csv").string());
      for (const auto& s : simulated) {
        const io::ManifestRow* row = manifest.Find((run / "bags" / s.bag).string());
        ASSERT_NE(row, nullptr) << s.bag;
        EXPECT_NEAR(std::stod(row->extras.at("true_hole_rate_pct")), s.hole_rate_pct, 0.001);
        ASSERT_TRUE(extracted.count(s.bag)) << s.bag;
        ASSERT_TRUE(extracted[s.bag].ok()) << s.bag << ": " << extracted[s.bag].message;
        ASSERT_TRUE(s.ok()) << s.bag << ": " << s.message;
        pairs.emplace_back(extracted[s.bag], s);
      }
      fs::remove_all(run / "bags");
    }
  }
  ASSERT_EQ(pairs.size(), 128u);

  std::printf("%-16s %8s %12s %12s %14s  %s\n", "column", "beyond", "max |diff|", "(tol there)",
              "max diff/tol", "worst cell");
  int cells_differing = 0;
  std::vector<bool> differs(pairs.size(), false);
  for (const Column& c : Columns()) {
    int beyond = 0;
    double worst = 0, worst_diff = 0, worst_tol = 0, max_abs = 0;
    std::string worst_bag;
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const auto& [e, s] = pairs[k];
      const double diff = c.relative ? c.value(e) / c.value(s) - 1.0 : c.value(e) - c.value(s);
      const double tol = c.tolerance(s);
      max_abs = std::max(max_abs, std::fabs(diff));
      const double ratio = tol > 0 ? std::fabs(diff) / tol : (diff == 0 ? 0.0 : INFINITY);
      if (ratio > 1.0) {
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
  EXPECT_EQ(cells_differing, 0);
}

}  // namespace
}  // namespace depthbias
