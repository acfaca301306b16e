// Honest margins: the residual model is recovered from errors of known spread, the near guard
// never moves a near reading farther, the weighted fit keeps far rows' scatter out of near
// corrections, the safe distance covers what k promises out of sample (simulated noise and the
// article's data), and weights written before margins still load.
#include "model/margin.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "io/metrics_csv.h"
#include "io/weights_yaml.h"
#include "model/bias_model.h"
#include "model/fit_groups.h"
#include "model/margin_fit.h"
#include "synthetic.h"

namespace depthbias::model {
namespace {

const std::string kArticle = DEPTHBIAS_SOURCE_DIR "/config/data/paper_d455_outdoor.csv";

// σ(Z) = √(σ_place² + (c·Z²)²).
double Sigma(double placement_m, double c, double z) {
  return std::sqrt(placement_m * placement_m + std::pow(c * z * z, 2));
}

TEST(ResidualModel, MaximumLikelihoodRecoversPlacementAndNoise) {
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> depth(1.0, 17.0);
  std::vector<ResidualData> data(2);
  const double placement[2] = {0.05, 0.15}, c = 0.003;
  for (int g = 0; g < 2; ++g) {
    for (int i = 0; i < 6000; ++i) {
      const double z = depth(rng);
      const double e = Sigma(placement[g], c, z) * n(rng);
      data[static_cast<size_t>(g)].depth_m.push_back(z);
      data[static_cast<size_t>(g)].error2_m2.push_back(e * e);
    }
  }
  ResidualFitParams p;  // c pooled
  const ResidualFitResult r = FitResidualModel(data, p);
  ASSERT_TRUE(r.success) << r.message;
  ASSERT_EQ(r.models.size(), 2u);
  for (int g = 0; g < 2; ++g) {
    EXPECT_NEAR(r.models[g].placement_m, placement[g], 0.15 * placement[g]) << g;
    EXPECT_NEAR(r.models[g].noise_per_m, c, 0.05 * c) << g;
  }
  p.pool_noise = false;
  const ResidualFitResult apart = FitResidualModel(data, p);
  ASSERT_TRUE(apart.success) << apart.message;
  EXPECT_NEAR(apart.models[1].noise_per_m, c, 0.1 * c);
  // Degenerate input is refused with a reason, never a silent model.
  EXPECT_FALSE(FitResidualModel({}, p).success);
  EXPECT_FALSE(FitResidualModel({ResidualData{{1.0}, {NAN}}}, p).success);
}

TEST(NearGuard, NeverMovesANearReadingFarther) {
  const NearGuard g{5.0, 7.0};
  EXPECT_DOUBLE_EQ(g.Apply(4.5, 4.0), 4.0);   // farther at 4 m: left alone
  EXPECT_DOUBLE_EQ(g.Apply(3.6, 4.0), 3.6);   // nearer: applied
  EXPECT_DOUBLE_EQ(g.Apply(6.4, 6.0), 6.2);   // half-way between 5 and 7 m: half
  EXPECT_DOUBLE_EQ(g.Apply(8.5, 8.0), 8.5);   // beyond 7 m: in full
  double share = 0;
  g.Apply(4.5, 4.0, &share);
  EXPECT_EQ(share, 0.0);
  EXPECT_DOUBLE_EQ(NearGuard{}.Apply(4.5, 4.0), 4.5);  // off
  std::string why;
  EXPECT_FALSE((NearGuard{7.0, 5.0}).IsValid(&why));
}

// Rows of one scenario from the disparity model (δ = 0.1 px, k = 1) with noise of a known
// σ(Z) = √(0.02² + (0.004·Z²)²): 1 cm at 4 m, 1 m at 16 m. Rows repeated `copies` times with
// fresh noise (emitter rows of one test point are independent draws here).
std::vector<Sample> NoisyRows(unsigned seed, int copies = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<Sample> out;
  for (int c = 0; c < copies; ++c) {
    auto s = testing::DisparityTruth(0.1, [](double) { return 1.0; }, 0.0, seed);
    for (auto& x : s) {
      x.x.depth_m += Sigma(0.02, 0.004, x.x.depth_m) * n(rng);
      x.target_m = x.x.depth_m - x.distance_m;
      x.row = out.size();
      out.push_back(x);
    }
  }
  return out;
}

TEST(FitWithMargins, WeightsNearRowsAndRecoversTheNoiseGrowth) {
  const auto s = NoisyRows(3, 4);
  FitParams p;
  p.model = "disp_scale";
  p.margins.weighting = MarginParams::Weighting::kOn;  // the default point fit is unweighted
  const JointFitResult r = FitWithMargins({s}, p);
  ASSERT_TRUE(r.success) << r.message;
  const FitResult& f = r.fits[0];
  EXPECT_TRUE(f.margin_weighted);
  ASSERT_TRUE(f.residual_model.known);
  EXPECT_NEAR(f.residual_model.noise_per_m, 0.004, 0.0015);
  const Features near{4.0, 0.0}, far{16.0, 0.0};
  EXPECT_LT(PredictiveStd(f, near), 0.1);
  EXPECT_GT(PredictiveStd(f, far), 0.6);
  EXPECT_GT(PredictiveStd(f, far), 10 * PredictiveStd(f, near));  // ∝ Z² beyond placement
}

// Far rows' scatter does not move near corrections: with 1 m of noise at 16 m and 3 cm at 4 m,
// the weighted fit's correction of a 4 m reading stays within a few centimetres of the true one,
// closer than the unweighted fit's (the guard off: the weighting alone).
TEST(FitWithMargins, NearReadingsAreNotMovedByFarRowsScatter) {
  FitParams weighted;
  weighted.model = "disp_scale";
  weighted.margins.guard = NearGuard{};
  weighted.margins.weighting = MarginParams::Weighting::kOn;
  FitParams plain = weighted;
  plain.margins.weighting = MarginParams::Weighting::kOff;
  const auto truth = testing::DisparityTruth(0.1, [](double) { return 1.0; }, 0.0, 1);
  double w_sum = 0.0, u_sum = 0.0;
  int n = 0;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const auto s = NoisyRows(30 + seed, 2);
    const JointFitResult w = FitWithMargins({s}, weighted), u = FitWithMargins({s}, plain);
    ASSERT_TRUE(w.success && u.success) << w.message << u.message;
    for (const auto& t : truth) {
      if (t.distance_m != 4.0) continue;
      w_sum += std::fabs(PredictBias(w.fits[0], t.x) - t.target_m);
      u_sum += std::fabs(PredictBias(u.fits[0], t.x) - t.target_m);
      ++n;
    }
  }
  EXPECT_LT(w_sum / n, 0.03);
  EXPECT_LT(w_sum, 0.5 * u_sum) << "weighted " << w_sum / n << " m, unweighted " << u_sum / n;
}

// Out of sample on rows of known noise: corrected − 2σ leaves at most 2.5 % of truths beyond it
// at every distance (4 scenarios × 32 rows).
TEST(Coverage, SafeDistanceCoversWhatKPromisesOnSimulatedNoise) {
  std::vector<records::PanelMetrics> rows;
  const char* scenarios[4][2] = {{"daylight", "HA"}, {"daylight", "HD"}, {"sunset", "HA"},
                                 {"sunset", "HD"}};
  for (int g = 0; g < 4; ++g) {
    for (const auto& s : NoisyRows(20 + g)) {
      records::PanelMetrics m;
      m.bag = "r" + std::to_string(rows.size());
      m.light = scenarios[g][0];
      m.preset = scenarios[g][1];
      m.emitter = s.row < 16 ? "on" : "off";
      m.distance_m = s.distance_m;
      m.angle_deg = s.angle_deg;
      m.median_m = m.mean_m = s.x.depth_m;
      rows.push_back(m);
    }
  }
  FitGroupsParams p;
  p.cv = {CvScheme::kPoint};
  const FitReport report = FitGroups(rows, p);
  ASSERT_TRUE(report.success) << report.message;
  const auto coverage = Coverage(report, 2.0);
  ASSERT_EQ(coverage.size(), 4u);
  for (const auto& c : coverage) {
    EXPECT_EQ(c.n, 32);
    EXPECT_LE(c.beyond, 0.025 * c.n) << c.distance_m << " m";
  }
  EXPECT_LT(coverage.front().mean_std_m, coverage.back().mean_std_m);
  EXPECT_NE(FormatCoverageTable(report, 2.0).find("daylight/HA"), std::string::npos);
}

// The article's data (scripts/coverage_table.sh prints the table), leave one test point out, the
// point fit unweighted (chosen for its error in metres) and σ fitted to its held-out errors:
// k = 2 leaves no truth beyond the safe distance at 4 and 12 m, and two rows each at 8 m (the
// daylight/HD 8 m 10° pair: one placement, both rows read +0.43 m where their neighbours read
// short) and at 16 m (daylight/HA 16 m 20°, whose emitter-on row has 5 % valid pixels and reads
// +3.9 m); 4 of 128 in all (3.1 % against the normal promise of 2.3 %: p = 0.16 per distance).
// σ grows with range in every scenario, and near readings are not pushed farther: the held-out
// mean signed error at 4 m is at most +0.05 m in every scenario (the near guard leaves them
// alone; it is negative, the safe side, where the camera reads short).
TEST(Coverage, ArticleDataLeaveOneTestPointOut) {
  const auto rows = io::ReadMetricsCsv(kArticle);
  FitGroupsParams p;
  p.cv = {CvScheme::kPoint};
  const FitReport report = FitGroups(rows, p);
  ASSERT_TRUE(report.success) << report.message;
  const auto coverage = Coverage(report, 2.0);
  ASSERT_EQ(coverage.size(), 4u);
  int beyond = 0;
  for (const auto& c : coverage) {
    EXPECT_LE(c.beyond, c.distance_m == 4 || c.distance_m == 12 ? 0 : 2) << c.distance_m << " m";
    beyond += c.beyond;
    // σ not too wide (rms of error/σ above 0.6), and at 8 m and beyond not too narrow either;
    // at 4 m the errors are the camera's own short readings, which the guard leaves on the safe
    // side.
    EXPECT_GT(c.rms_z, 0.6) << c.distance_m << " m";
    EXPECT_LT(c.rms_z, c.distance_m == 4 ? 2.5 : 1.5) << c.distance_m << " m";
    EXPECT_GT(c.promise_p, 0.1) << c.distance_m << " m";  // misses the promise can explain
    for (size_t g = 0; g < c.group_mean_error_m.size(); ++g) {
      if (c.distance_m == 4.0) {
        EXPECT_LE(c.group_mean_error_m[g], 0.05) << report.groups[g].group.Label();
      }
    }
  }
  EXPECT_LE(beyond, 4);
  EXPECT_LT(coverage[0].mean_std_m, 0.5);  // a 4 m reading keeps a useful safe distance
  for (const auto& g : report.groups) {
    EXPECT_LT(PredictiveStd(g.fit, {4.0, 0.0}), PredictiveStd(g.fit, {16.0, 0.0}))
        << g.group.Label();
  }
}

// Weights of schema 1 (before margins) still load: σ is their constant residual std, no guard.
TEST(WeightsSchema, OlderWeightsLoadWithTheirConstantSigma) {
  const std::string v1 = R"(schema: depthbias.weights/1
model: disp_scale
lambda: 0.001
focal_px: 640
baseline_m: 0.095
groups:
  - {light: daylight, preset: HD, n: 32, weights: {delta_px: 0.1, k: 1.0}, rmse_m: 0.3,
     mae_m: 0.2, residual_std_m: 0.5, covariance: []}
)";
  const records::BiasWeights w = io::ParseWeightsYaml(v1, "old.yaml");
  EXPECT_FALSE(w.groups[0].margin.known);
  const BiasModel model(w);
  const auto& s = model.Scenario("daylight", "HD");
  EXPECT_FALSE(s.has_margin());
  EXPECT_DOUBLE_EQ(s.PredictiveStdM(4.0, 0.0), 0.5);
  EXPECT_DOUBLE_EQ(s.PredictiveStdM(16.0, 0.0), 0.5);
  EXPECT_FALSE(s.NearGuarded(4.0, 0.0));
  // Schema 1 has no margin keys; schema 2 refuses unknown ones inside them.
  EXPECT_THROW(io::ParseWeightsYaml(v1 + "near_guard: {near_m: 5, full_m: 7}\n", "old.yaml"),
               io::IoError);
  std::string v2 = v1;
  v2.replace(v2.find("/1"), 2, "/2");
  v2.replace(v2.find("residual_std_m: 0.5,"), 20,
             "residual_std_m: 0.5, margin: {placement_m: 0.1, noise_per_m: 0.001, wide: 1},");
  try {
    io::ParseWeightsYaml(v2, "new.yaml");
    ADD_FAILURE() << "an unknown margin key was accepted";
  } catch (const io::IoError& e) {
    EXPECT_NE(std::string(e.what()).find("margin.wide"), std::string::npos) << e.what();
  }
}

TEST(WeightsSchema, MarginAndGuardRoundTrip) {
  FitGroupsParams p;
  const FitReport report = FitGroups(io::ReadMetricsCsv(kArticle), p);
  ASSERT_TRUE(report.success) << report.message;
  const records::BiasWeights w = ToWeights(report, p);
  const records::BiasWeights back =
      io::ParseWeightsYaml(io::FormatWeightsYaml(w), "w.yaml");
  EXPECT_EQ(back.schema, "depthbias.weights/2");
  EXPECT_EQ(back.near_m, 5.0);
  EXPECT_EQ(back.full_m, 7.0);
  EXPECT_TRUE(back.noise_pooled);
  const BiasModel a(w), b(back);
  for (const auto& g : report.groups) {
    const auto& sa = a.Scenario(g.group.light, g.group.preset);
    const auto& sb = b.Scenario(g.group.light, g.group.preset);
    EXPECT_TRUE(sb.has_margin());
    for (double z : {3.5, 6.0, 9.0, 15.0}) {
      EXPECT_DOUBLE_EQ(sa.PredictiveStdM(z, 12.0), sb.PredictiveStdM(z, 12.0));
      EXPECT_DOUBLE_EQ(sa.CorrectedM(z, 12.0), sb.CorrectedM(z, 12.0));
      // The model's σ is the fit's.
      EXPECT_NEAR(sa.PredictiveStdM(z, 12.0),
                  PredictiveStd(g.fit, {z, 12.0 * M_PI / 180.0}), 1e-9);
    }
  }
}

}  // namespace
}  // namespace depthbias::model
