#include "model/bias_model.h"

#include <gtest/gtest.h>

#include "model/fit_groups.h"
#include "synthetic.h"

namespace depthbias::model {
namespace {

// Rows of two scenarios generated from known disparity models.
std::vector<records::PanelMetrics> Rows() {
  std::vector<records::PanelMetrics> rows;
  for (const char* preset : {"HA", "HD"}) {
    const double delta = std::string(preset) == "HA" ? 0.25 : -0.2;
    const auto s = testing::DisparityTruth(delta, [](double a) { return 1.0 - 0.002 * a; },
                                           0.02, 4);
    for (size_t i = 0; i < s.size(); ++i) {
      records::PanelMetrics m;
      m.bag = std::string(preset) + std::to_string(i);
      m.light = "daylight";
      m.preset = preset;
      m.emitter = i < 16 ? "on" : "off";
      m.distance_m = s[i].distance_m;
      m.angle_deg = s[i].angle_deg;
      m.median_m = m.mean_m = s[i].x.depth_m;
      m.valid_pct = 50;
      m.frames = 300;
      rows.push_back(m);
    }
  }
  return rows;
}

records::BiasWeights Weights() {
  FitGroupsParams p;
  const FitReport report = FitGroups(Rows(), p);
  EXPECT_TRUE(report.success) << report.message;
  return ToWeights(report, p);
}

TEST(FitGroups, RefusesMeasuredRowsWithoutGroundTruthAndSkipsFailedOnes) {
  auto rows = Rows();
  rows[3].status = "no_panel";
  rows[3].distance_m = records::PanelMetrics::kMissing;
  FitGroupsParams p;
  const FitReport skipped = FitGroups(rows, p);
  ASSERT_TRUE(skipped.success) << skipped.message;
  EXPECT_EQ(skipped.rows_skipped, 1);
  rows[5].angle_deg = records::PanelMetrics::kMissing;
  const FitReport refused = FitGroups(rows, p);
  EXPECT_FALSE(refused.success);
  EXPECT_NE(refused.message.find(rows[5].bag), std::string::npos) << refused.message;
  EXPECT_NE(refused.message.find("ground truth"), std::string::npos) << refused.message;
}

TEST(BiasModel, ReproducesTheFitAndCorrectsTowardsTruth) {
  const auto rows = Rows();
  FitGroupsParams p;
  const FitReport report = FitGroups(rows, p);
  ASSERT_TRUE(report.success) << report.message;
  ASSERT_EQ(report.groups.size(), 2u);
  const BiasModel model(ToWeights(report, p));
  for (const auto& g : report.groups) {
    const auto& s = model.Scenario(g.group.light, g.group.preset);
    for (size_t i : g.group.rows) {
      const auto& r = rows[i];
      const Features x{r.median_m, r.angle_deg * M_PI / 180.0};
      EXPECT_NEAR(s.BiasM(r.median_m, r.angle_deg), PredictBias(g.fit, x), 1e-12);
      EXPECT_NEAR(s.PredictiveStdM(r.median_m, r.angle_deg), PredictiveStd(g.fit, x), 1e-9);
      // Noise 2 cm: corrected distances land near the truth, except near readings the guard
      // leaves (partly) alone: those stay between the measured range and the truth, on the
      // near (safe) side.
      const double corrected = s.CorrectedM(r.median_m, r.angle_deg);
      if (s.NearGuarded(r.median_m, r.angle_deg)) {
        EXPECT_GE(corrected, ScenarioModel::RawRangeM(r.median_m, r.angle_deg) - 1e-9);
        EXPECT_LT(corrected, r.distance_m + 0.05);
      } else {
        EXPECT_NEAR(corrected, r.distance_m, 0.1);
      }
    }
  }
}

TEST(BiasModel, SafeDistanceIsCorrectedMinusKStd) {
  const BiasModel model(Weights());
  const auto& s = model.Scenario("daylight", "HD", "on");
  const double c = s.CorrectedM(10.0, 15.0), sd = s.PredictiveStdM(10.0, 15.0);
  EXPECT_GT(sd, 0.0);
  EXPECT_DOUBLE_EQ(s.SafeDistanceM(10.0, 15.0, 3.0), c - 3.0 * sd);
  EXPECT_LT(s.SafeDistanceM(10.0, 15.0, 3.0), s.SafeDistanceM(10.0, 15.0, 1.0));
}

TEST(BiasModel, UnknownScenarioIsRefusedWithTheKnownOnes) {
  const BiasModel model(Weights());
  EXPECT_TRUE(model.Has("daylight", "HA"));
  EXPECT_FALSE(model.Has("sunset", "HA"));
  try {
    model.Scenario("sunset", "HA");
    FAIL();
  } catch (const std::out_of_range& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("sunset"), std::string::npos) << w;
    EXPECT_NE(w.find("daylight/HD"), std::string::npos) << w;
  }
}

TEST(BiasModel, CloudPointsMoveAlongTheirRayToTheCorrectedRange) {
  const BiasModel model(Weights());
  const auto& s = model.Scenario("daylight", "HA");
  std::vector<Eigen::Vector3d> cloud = {{0.0, 0.0, 8.0}, {3.0, -1.0, 9.0}, {0.0, 0.0, -1.0}};
  const auto before = cloud;
  EXPECT_EQ(s.CorrectCloud(&cloud), 1);  // the point behind the camera is left alone
  EXPECT_EQ(cloud[2], before[2]);
  for (int i = 0; i < 2; ++i) {
    const Eigen::Vector3d& p = before[i];
    const double angle_deg = std::atan2(std::hypot(p.x(), p.y()), p.z()) * 180.0 / M_PI;
    EXPECT_NEAR(cloud[i].normalized().dot(p.normalized()), 1.0, 1e-12);  // same ray
    EXPECT_NEAR(cloud[i].norm(), s.CorrectedM(p.z(), angle_deg), 1e-9);  // corrected range
  }
}

TEST(BiasModel, WeightsThatDoNotMatchTheModelAreRefused) {
  auto w = Weights();
  w.groups[0].names[0] = "offset";
  EXPECT_THROW(BiasModel{w}, std::invalid_argument);
  w = Weights();
  w.groups[0].values.pop_back();
  w.groups[0].names.pop_back();
  EXPECT_THROW(BiasModel{w}, std::invalid_argument);
  w = Weights();
  w.model = "spline";
  EXPECT_THROW(BiasModel{w}, std::invalid_argument);
  w = Weights();
  w.groups[1].covariance.pop_back();
  EXPECT_THROW(BiasModel{w}, std::invalid_argument);
}

TEST(FitGroups, GroupWithTooFewRowsFailsNamingIt) {
  auto rows = Rows();
  rows.resize(35);  // HD keeps 3 rows, for 4 parameters (δ and three knots)
  FitGroupsParams p;
  const FitReport r = FitGroups(rows, p);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("daylight/HD"), std::string::npos) << r.message;
}

TEST(FitGroups, CrossValidationTheDesignCannotSupportIsAWarning) {
  std::vector<records::PanelMetrics> rows;
  for (const auto& r : Rows()) {
    if (r.distance_m <= 8) rows.push_back(r);  // two distances: one left out leaves one
  }
  FitGroupsParams p;
  const FitReport r = FitGroups(rows, p);
  ASSERT_TRUE(r.success) << r.message;
  ASSERT_EQ(r.warnings.size(), 2u);  // one per group
  EXPECT_NE(r.warnings[0].find("distance cross-validation"), std::string::npos) << r.warnings[0];
  EXPECT_TRUE(r.groups[0].cv[0].success);  // leave one point out still runs
  EXPECT_TRUE(std::isnan(r.groups[0].cv[1].rmse_m));
}

}  // namespace
}  // namespace depthbias::model
