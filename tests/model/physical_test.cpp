// What has no physical meaning is refused before anything is computed: weights with a negative
// depth scale, σ terms that overflow, knots or readings at 80° off axis or beyond, medians nearer
// than the camera's minimum range. The model takes the signed off-axis angle and uses |α|.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "model/bias_model.h"
#include "model/domain.h"
#include "model/fit_groups.h"
#include "synthetic.h"

namespace depthbias::model {
namespace {

std::vector<records::PanelMetrics> Rows() {
  std::vector<records::PanelMetrics> rows;
  const auto s = testing::DisparityTruth(0.2, [](double a) { return 1.0 - 0.002 * a; }, 0.02, 4);
  for (size_t i = 0; i < s.size(); ++i) {
    records::PanelMetrics m;
    m.bag = "r" + std::to_string(i);
    m.light = "daylight";
    m.preset = "HA";
    m.emitter = i < 16 ? "on" : "off";
    m.distance_m = s[i].distance_m;
    m.angle_deg = s[i].angle_deg;
    m.median_m = m.mean_m = s[i].x.depth_m;
    m.valid_pct = 50;
    m.frames = 300;
    rows.push_back(m);
  }
  return rows;
}

records::BiasWeights Weights(const std::string& model) {
  FitGroupsParams p;
  p.fit.model = model;
  p.cv = {};
  const FitReport report = FitGroups(Rows(), p);
  EXPECT_TRUE(report.success) << report.message;
  return ToWeights(report, p);
}

std::string Refusal(const records::BiasWeights& w) {
  try {
    BiasModel m(w);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(Physical, FittedWeightsAreAccepted) {
  for (const char* m : {"disp_knots", "disp_tan", "disp_scale", "paper6"})
    EXPECT_EQ(Refusal(Weights(m)), "") << m;
}

TEST(Physical, NegativeOrZeroScalesAreRefused) {
  auto w = Weights("disp_scale");
  ASSERT_EQ(w.groups[0].names[1], "k");
  w.groups[0].values[1] = -0.5;
  EXPECT_NE(Refusal(w).find("weight 'k' is -0.5: a depth scale must be > 0"), std::string::npos)
      << Refusal(w);
  w.groups[0].values[1] = 0.0;
  EXPECT_NE(Refusal(w).find("depth scale"), std::string::npos);
  auto knots = Weights("disp_knots");
  knots.groups[0].values[2] = -1.0;  // k at the second knot
  EXPECT_NE(Refusal(knots).find("depth scale must be > 0"), std::string::npos);
  // disp_tan: k0 > 0 but k(α) = k0 + k1·tanα + k2·tan²α crosses zero within the field of view.
  auto tan = Weights("disp_tan");
  tan.groups[0].values[3] = -2.0;  // k2
  EXPECT_NE(Refusal(tan).find("off axis is -"), std::string::npos) << Refusal(tan);
}

TEST(Physical, SigmaTermsThatOverflowAreRefused) {
  auto w = Weights("disp_knots");
  ASSERT_TRUE(w.groups[0].margin.known);
  w.groups[0].margin.noise_per_m = 1e160;  // (c·Z²)² overflows
  EXPECT_NE(Refusal(w).find("is not a finite distance"), std::string::npos) << Refusal(w);
  w = Weights("disp_knots");
  w.groups[0].margin.placement_m = std::numeric_limits<double>::infinity();
  EXPECT_NE(Refusal(w).find("is not a finite distance"), std::string::npos) << Refusal(w);
  w = Weights("disp_knots");
  ASSERT_FALSE(w.groups[0].covariance.empty());
  for (auto& row : w.groups[0].covariance)
    for (double& c : row) c = 1e307;  // a rank-one PSD matrix whose gᵀΣg overflows
  EXPECT_NE(Refusal(w).find("not finite numbers"), std::string::npos) << Refusal(w);
}

TEST(Physical, KnotsAtEightyDegreesOrBeyondAreRefused) {
  auto w = Weights("disp_knots");
  ASSERT_EQ(w.groups[0].knots_deg.size(), 4u);
  w.groups[0].knots_deg.back() = 80.0;
  w.groups[0].names.back() = "k_80deg";
  EXPECT_NE(Refusal(w).find("knot 80 deg is at or beyond 80 deg"), std::string::npos)
      << Refusal(w);
}

TEST(Physical, ReadingsOutsideTheDomainHaveNoPrediction) {
  EXPECT_EQ(OutsideDomain(4.0, 35.0), "");
  EXPECT_EQ(OutsideDomain(4.0, -79.9), "");
  EXPECT_NE(OutsideDomain(0.1, 0.0).find("nearer than the camera's minimum range 0.4 m"),
            std::string::npos);
  EXPECT_NE(OutsideDomain(4.0, 80.0).find("at or beyond 80 deg"), std::string::npos);
  EXPECT_NE(OutsideDomain(4.0, -89.9).find("at or beyond 80 deg"), std::string::npos);
  const BiasModel m(Weights("paper6"));
  const auto& s = m.Scenario("daylight", "HA");
  EXPECT_TRUE(std::isfinite(s.CorrectedM(8.0, 20.0)));
  EXPECT_TRUE(std::isnan(s.CorrectedM(8.0, 89.9)));  // was hundreds of kilometres
  EXPECT_TRUE(std::isnan(s.PredictiveStdM(8.0, 85.0)));
  EXPECT_TRUE(std::isnan(s.CorrectedM(0.05, 0.0)));
}

// One rule for the sign of α: the model takes the signed off-axis angle and applies |α| itself,
// so a −20° reading is corrected as a 20° one (paper6's tanα terms are odd: without the rule a
// −20° reading gets another correction).
TEST(Physical, ANegativeAngleIsCorrectedAsItsMirror) {
  for (const char* form : {"paper6", "disp_knots", "disp_tan"}) {
    const BiasModel m(Weights(form));
    const auto& s = m.Scenario("daylight", "HA");
    for (double a : {10.0, 20.0, 27.0, 35.0}) {
      EXPECT_DOUBLE_EQ(s.CorrectedM(9.0, -a), s.CorrectedM(9.0, a)) << form << " " << a;
      EXPECT_DOUBLE_EQ(s.PredictiveStdM(9.0, -a), s.PredictiveStdM(9.0, a)) << form << " " << a;
    }
    EXPECT_NE(s.CorrectedM(9.0, 20.0), s.CorrectedM(9.0, 0.0)) << form;
  }
  // Fitting: rows at −α are the rows at α (same test point, same knot).
  auto rows = Rows();
  for (auto& r : rows) r.angle_deg = -r.angle_deg;
  FitGroupsParams p;
  p.fit.model = "paper6";
  p.cv = {CvScheme::kPoint};
  const FitReport neg = FitGroups(rows, p), pos = FitGroups(Rows(), p);
  ASSERT_TRUE(neg.success && pos.success) << neg.message << pos.message;
  for (size_t j = 0; j < pos.groups[0].fit.values.size(); ++j)
    EXPECT_NEAR(neg.groups[0].fit.values[j], pos.groups[0].fit.values[j], 1e-9);
  EXPECT_EQ(neg.groups[0].cv[0].folds, pos.groups[0].cv[0].folds);
}

TEST(Physical, FitGroupsRefusesReadingsOutsideTheDomain) {
  auto rows = Rows();
  rows[7].median_m = 0.1;
  FitGroupsParams p;
  FitReport r = FitGroups(rows, p);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("bag 'r7': median 0.1 m is nearer"), std::string::npos) << r.message;
  rows = Rows();
  rows[3].angle_deg = 85.0;
  r = FitGroups(rows, p);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("bag 'r3': angle 85 deg is at or beyond 80 deg"), std::string::npos)
      << r.message;
  rows[3].status = "no_panel";  // a failed row is skipped, whatever its numbers
  EXPECT_TRUE(FitGroups(rows, p).success);
}

}  // namespace
}  // namespace depthbias::model
