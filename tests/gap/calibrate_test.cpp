// Calibration recovers the noise and hole probability that made a table.
#include <gtest/gtest.h>

#include "gap/calibrate.h"

namespace depthbias::gap {
namespace {

TEST(Calibrate, RecoversTheScenarioThatMadeTheTable) {
  sim::SimParams truth;
  truth.seed = 3;
  truth.sensor.scenarios = {{"daylight", "HA", 0.06, 0.4}, {"sunset", "HD", 0.09, 0.15}};
  truth.protocol.distances_m = {4, 8, 12};
  truth.protocol.angles_deg = {0, 20};
  truth.protocol.emitters = {false};
  truth.protocol.presets = {"HA", "HD"};
  std::vector<records::PanelMetrics> table;
  sim::MetricsParams mp;
  mp.frames = CalibrateParams{}.frames;
  for (const sim::Cell& c : sim::MakeCells(truth.protocol)) {
    if ((c.light == "daylight") != (c.preset == "HA")) continue;
    table.push_back(sim::SimulateMetrics(truth, c, mp).metrics);
  }
  ASSERT_EQ(table.size(), 12u);
  records::PanelMetrics broken = table[0];
  broken.status = "no_panel";
  table.push_back(broken);

  sim::SimParams start = truth;
  start.sensor.scenarios.clear();  // start from the fallback: σ_d 0.08 px, p 0.2
  const CalibrationResult r = CalibrateSensor(start, table);
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_EQ(r.rows_used, 12);
  EXPECT_EQ(r.rows_skipped, 1);
  ASSERT_EQ(r.scenarios.size(), 2u);
  for (const auto& fit : r.scenarios) {
    const sim::ScenarioParams want = truth.sensor.Scenario(fit.fitted.light, fit.fitted.preset);
    EXPECT_NEAR(fit.fitted.sigma_d_px, want.sigma_d_px, 0.03 * want.sigma_d_px)
        << fit.fitted.light << " " << fit.report;
    EXPECT_NEAR(fit.fitted.invalid_prob, want.invalid_prob, 0.01) << fit.fitted.light;
    EXPECT_LT(fit.rms_log_plane_std, 0.03);
    EXPECT_LT(fit.rms_valid_pct, 1.0);
    EXPECT_EQ(fit.cells.size(), 6u);
  }
  bool found = false;
  r.sensor.Scenario("sunset", "HD", &found);
  EXPECT_TRUE(found);
  EXPECT_NE(CalibrationYaml(r, "table.csv").find("rms_valid_pct"), std::string::npos);
}

TEST(Calibrate, SaysWhyWithoutUsableRows) {
  records::PanelMetrics row;
  row.status = "error";
  const CalibrationResult r = CalibrateSensor(sim::SimParams{}, {row});
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("no usable rows"), std::string::npos) << r.message;
}

}  // namespace
}  // namespace depthbias::gap
