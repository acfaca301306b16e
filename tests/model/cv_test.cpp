#include "model/cv.h"

#include <set>

#include <gtest/gtest.h>

#include "synthetic.h"

namespace depthbias::model {
namespace {

TEST(Folds, PointFoldsKeepBothEmitterRowsTogether) {
  const auto s = testing::ArticleDesign();
  const auto ids = FoldIds(s, CvScheme::kPoint);
  EXPECT_EQ(std::set<int>(ids.begin(), ids.end()).size(), 16u);
  for (size_t i = 0; i < s.size(); ++i) {
    for (size_t j = 0; j < s.size(); ++j) {
      const bool same_point = s[i].distance_m == s[j].distance_m &&
                              s[i].angle_deg == s[j].angle_deg;
      EXPECT_EQ(ids[i] == ids[j], same_point);
    }
  }
  const auto d = FoldIds(s, CvScheme::kDistance);
  EXPECT_EQ(std::set<int>(d.begin(), d.end()).size(), 4u);
  for (size_t i = 0; i < s.size(); ++i) {
    for (size_t j = 0; j < s.size(); ++j) {
      EXPECT_EQ(d[i] == d[j], s[i].distance_m == s[j].distance_m);
    }
  }
}

TEST(CrossValidate, NoiseFreeTruthIsPredictedOutOfSample) {
  const auto s = testing::DisparityTruth(0.3, [](double a) { return 1.0 - 0.001 * a; }, 0.0, 1);
  FitParams p;
  p.model = "disp_knots";
  p.lambda = 0.0;
  for (CvScheme scheme : {CvScheme::kPoint, CvScheme::kDistance}) {
    const CvResult r = CrossValidate(s, p, scheme);
    ASSERT_TRUE(r.success) << r.message;
    EXPECT_LT(r.rmse_m, 1e-6) << CvSchemeName(scheme);
  }
}

TEST(CrossValidate, HeldOutErrorExceedsInSampleErrorWithNoise) {
  const auto s = testing::DisparityTruth(0.3, [](double) { return 1.0; }, 0.1, 11);
  FitParams p;
  p.model = "paper6";
  const FitResult f = Fit(s, p);
  const CvResult r = CrossValidate(s, p, CvScheme::kPoint);
  ASSERT_TRUE(f.success && r.success);
  EXPECT_GT(r.rmse_m, f.rmse_m);
  EXPECT_EQ(r.folds, 16);
  for (double e : r.errors_m) EXPECT_TRUE(std::isfinite(e));
}

TEST(CrossValidate, DistanceFoldsWithTooFewDistancesFailWithReason) {
  auto s = testing::DisparityTruth(0.3, [](double) { return 1.0; }, 0.0, 1);
  std::vector<Sample> two;
  for (const auto& x : s) {
    if (x.distance_m <= 8) two.push_back(x);
  }
  FitParams p;
  p.model = "disp_scale";
  const CvResult r = CrossValidate(two, p, CvScheme::kDistance);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("singular"), std::string::npos) << r.message;
}

TEST(NestedCrossValidate, PicksTheTrueFormOnCleanData) {
  const auto s = testing::DisparityTruth(
      0.3, [](double a) { return a == 20 ? 1.05 : 0.97; }, 0.005, 5);
  std::vector<FitParams> candidates(2);
  candidates[0].model = "disp_scale";
  candidates[1].model = "disp_knots";
  std::vector<int> chosen;
  const CvResult r = NestedCrossValidate(s, candidates, CvScheme::kPoint, &chosen);
  ASSERT_TRUE(r.success) << r.message;
  ASSERT_EQ(chosen.size(), 16u);
  for (int c : chosen) EXPECT_EQ(c, 1);
  EXPECT_LT(r.rmse_m, 0.02);
}

}  // namespace
}  // namespace depthbias::model
