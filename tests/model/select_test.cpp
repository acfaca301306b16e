// The point fit chosen by held-out RMSE in metres, the choice made again inside every fold; leave
// one angle out; a margin that falls back to in-sample residuals says so.
#include "model/select.h"

#include <set>

#include <gtest/gtest.h>

#include "io/weights_yaml.h"
#include "model/fit_groups.h"
#include "model/margin_fit.h"
#include "synthetic.h"

namespace depthbias::model {
namespace {

TEST(Folds, AngleFoldsHoldEveryRowOfOneAngle) {
  const auto s = testing::ArticleDesign();
  const auto ids = FoldIds(s, CvScheme::kAngle);
  EXPECT_EQ(std::set<int>(ids.begin(), ids.end()).size(), 4u);
  for (size_t i = 0; i < s.size(); ++i)
    for (size_t j = 0; j < s.size(); ++j)
      EXPECT_EQ(ids[i] == ids[j], s[i].angle_deg == s[j].angle_deg);
  CvScheme scheme;
  ASSERT_TRUE(ParseCvScheme("angle", &scheme));
  EXPECT_EQ(scheme, CvScheme::kAngle);
  EXPECT_EQ(CvSchemeName(CvScheme::kAngle), "angle");
}

// A scale that changes smoothly with the angle (k = 1 − 0.004·α): leaving an angle out, the
// smooth form (disp_tan) predicts the missing angle and a single scale (disp_scale) cannot.
TEST(CrossValidate, LeavingAnAngleOutJudgesWhatTheFormSaysBetweenAngles) {
  const auto s = testing::DisparityTruth(0.2, [](double a) { return 1.0 - 0.004 * a; }, 0.0, 1);
  FitParams smooth, flat;
  smooth.model = "disp_tan";
  flat.model = "disp_scale";
  smooth.lambda = flat.lambda = 0.0;
  const CvResult rs = CrossValidate(s, smooth, CvScheme::kAngle);
  const CvResult rf = CrossValidate(s, flat, CvScheme::kAngle);
  ASSERT_TRUE(rs.success && rf.success) << rs.message << rf.message;
  EXPECT_EQ(rs.folds, 4);
  EXPECT_LT(rs.rmse_m, 0.05);
  EXPECT_GT(rf.rmse_m, 3 * rs.rmse_m);
}

// The choice follows the data: a truth with a per-angle scale and noise is best told by a
// disparity-space form, never by eq. 6; the choice is made again in every fold and the held-out
// rows of a fold never take part in it.
TEST(Selector, ChoosesByHeldOutRmseAndAgainInEveryFold) {
  std::vector<std::vector<Sample>> unit;
  for (unsigned seed : {3u, 4u})
    unit.push_back(testing::DisparityTruth(0.25, [](double a) { return 1.0 - 0.003 * a; }, 0.03,
                                           seed));
  FitParams base;
  Selector selector(unit, SelectionCandidates(base));
  ASSERT_EQ(selector.candidates().size(), 8u);
  const int c = selector.Choose();
  ASSERT_GE(c, 0);
  EXPECT_NE(selector.candidates()[static_cast<size_t>(c)].model, "paper6") << selector.Label(c);
  const auto rmse = selector.PooledRmse();
  for (size_t i = 0; i < rmse.size(); ++i) EXPECT_LE(rmse[static_cast<size_t>(c)], rmse[i]);
  // A fold's choice sees only its training rows: rows made absurd in the held-out fold cannot
  // change it.
  auto broken = unit;
  const auto folds = FoldIds(broken[0], CvScheme::kDistance);
  for (size_t i = 0; i < broken[0].size(); ++i)
    if (folds[i] == 0) broken[0][i].target_m += 5.0;
  Selector clean(unit, SelectionCandidates(base)), dirty(broken, SelectionCandidates(base));
  auto fixed = [](int) { return std::vector<ResidualData>{}; };
  const CvResult a = CrossValidateSelected(&clean, 0, CvScheme::kDistance, fixed);
  const CvResult b = CrossValidateSelected(&dirty, 0, CvScheme::kDistance, fixed);
  ASSERT_TRUE(a.success && b.success) << a.message << b.message;
  ASSERT_EQ(a.chosen.size(), 4u);
  EXPECT_EQ(a.chosen[0], b.chosen[0]);
}

// A design where a test point cannot be left out (the only row pair at 20°: without it disp_tan
// has two angles): the margin falls back to in-sample residuals, and says so in the report and
// in the weights.
TEST(FitGroups, AMarginOnInSampleResidualsIsWarnedAndRecorded) {
  std::vector<records::PanelMetrics> rows;
  for (const auto& s : testing::DisparityTruth(0.2, [](double) { return 0.98; }, 0.02, 5)) {
    if (s.angle_deg == 35.0 || (s.angle_deg == 20.0 && s.distance_m != 8.0)) continue;
    records::PanelMetrics m;
    m.bag = "r" + std::to_string(rows.size());
    m.light = "daylight";
    m.preset = "HA";
    m.emitter = "on";
    m.distance_m = s.distance_m;
    m.angle_deg = s.angle_deg;
    m.median_m = m.mean_m = s.x.depth_m;
    rows.push_back(m);
  }
  FitGroupsParams p;
  p.fit.model = "disp_tan";
  p.cv = {};
  const FitReport r = FitGroups(rows, p);
  ASSERT_TRUE(r.success) << r.message;
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("group daylight/HA: sigma fitted to in-sample residuals"),
            std::string::npos) << r.warnings[0];
  const auto w = ToWeights(r, p);
  EXPECT_EQ(w.groups[0].margin.errors, "in_sample");
  const std::string yaml = io::FormatWeightsYaml(w);
  EXPECT_NE(yaml.find("errors: in_sample"), std::string::npos) << yaml;
  EXPECT_EQ(io::ParseWeightsYaml(yaml, "w.yaml").groups[0].margin.errors, "in_sample");
  // The full design leaves every test point out: held-out errors, no warning.
  p.fit.model = "disp_knots";
  const FitReport full = FitGroups(rows, p);
  ASSERT_TRUE(full.success) << full.message;
  EXPECT_TRUE(full.warnings.empty());
  EXPECT_EQ(ToWeights(full, p).groups[0].margin.errors, "held_out");
}

}  // namespace
}  // namespace depthbias::model
