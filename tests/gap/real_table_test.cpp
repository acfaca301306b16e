// Effects injected by their physics into real tables (lib/gap/cases.h, RealInjectionCases):
// the map each row goes through, the cases' sizes from a table's own limits, and the article's
// 128 rows with a disparity offset beyond and below its limit, diagnosed as the tool diagnoses
// any table (the judge's reading against the table as it was: withheld_test.cpp, Criteria).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "gap/cases.h"
#include "gap/design.h"
#include "gap/diagnose.h"
#include "io/metrics_csv.h"
#include "sim/effects.h"
#include "sim/sim_metrics.h"
#include "support/article.h"

namespace depthbias::gap {
namespace {

sim::SimParams Base() { return test_support::ArticleSimParams(); }

// A disparity offset's limits on a table: −0.653 px over-reads by 2.93 m at its far end.
DetectionLimit OffsetLimit() {
  DetectionLimit offset;
  offset.effect = "disparity_offset";
  offset.param = "delta_px";
  offset.neutral = 0;
  offset.size = {-0.653, 0.764};
  offset.far_m = {2.93, -1.7};
  return offset;
}

// A daylight row at 16 m, measured.
records::PanelMetrics RowAt16() {
  records::PanelMetrics m;
  m.bag = "a";
  m.light = "daylight";
  m.distance_m = 16;
  m.median_m = 16;
  m.mean_m = 16.1;
  m.plane_std_m = 0.1;
  m.temporal_std_m = 0.05;
  m.panel_width_m = 1.02;
  m.panel_height_m = 0.98;
  m.normal_tilt_deg = 20;
  m.valid_pct = 40;
  return m;
}

// Effects injected into a real table's rows by their physics (InjectIntoRealTable): each row's
// depths through the effect's map, hand-computed at 16 m with f·B = 60 px·m.
TEST(RealTable, AnInjectionMapsEachRowByItsPhysics) {
  const records::PanelMetrics m = RowAt16();
  records::PanelMetrics sunset = m;
  sunset.light = "sunset";
  WithheldCase c;
  c.name = "offset";
  c.injected = {{"disparity_offset", {{"delta_px", -0.5}}, "daylight"}};
  const auto rows = InjectIntoRealTable({m, sunset}, c, 60, 1.0);
  ASSERT_EQ(rows.size(), 2u);
  const double z = 60 / (60 / 16.0 - 0.5), r = z / 16;  // 18.46 m: a negative offset reads far
  EXPECT_NEAR(rows[0].median_m, z, 1e-9);
  EXPECT_NEAR(rows[0].mean_m - rows[0].median_m, 0.1 * r * r, 1e-9);
  EXPECT_NEAR(rows[0].plane_std_m, 0.1 * r * r, 1e-12);
  EXPECT_NEAR(rows[0].temporal_std_m, 0.05 * r * r, 1e-12);
  // Read far, the window is the panel's known size on the plane: the extent stays.
  EXPECT_EQ(rows[0].panel_width_m, 1.02);
  EXPECT_EQ(rows[0].panel_height_m, 0.98);
  // The tilt is the plane fit's error: σ along the normal (r²) over √N of a window holding
  // N / r² of the pixels (r).
  EXPECT_NEAR(std::tan(rows[0].normal_tilt_deg * M_PI / 180),
              std::tan(20 * M_PI / 180) * r * r * r, 1e-9);
  EXPECT_EQ(rows[0].valid_pct, 40);
  EXPECT_EQ(rows[0].distance_m, 16) << "the nominal distance is the campaign's";
  EXPECT_EQ(rows[1].median_m, 16) << "the other light is left alone";
  c.injected = {{"depth_scale", {{"scale_rel", 0.1}}, ""}};
  const auto scaled = InjectIntoRealTable({m}, c, 60, 1.0);
  EXPECT_NEAR(scaled[0].median_m, 17.6, 1e-9);
  EXPECT_NEAR(scaled[0].mean_m, 17.71, 1e-9);
  EXPECT_NEAR(scaled[0].plane_std_m, 0.11, 1e-12);
  EXPECT_NEAR(std::tan(scaled[0].normal_tilt_deg * M_PI / 180),
              std::tan(20 * M_PI / 180) * 1.1 * 1.1, 1e-9);
  EXPECT_EQ(scaled[0].panel_width_m, 1.02);
  EXPECT_EQ(scaled[0].panel_height_m, 0.98);
  // Read near, the window takes in the background and the region keeps the panel's image: its
  // extent on the nearer plane shrinks by the depths' ratio, the bound the map applies.
  c.injected = {{"depth_scale", {{"scale_rel", -0.1}}, ""}};
  const auto nearer = InjectIntoRealTable({m}, c, 60, 1.0);
  EXPECT_NEAR(nearer[0].panel_width_m, 1.02 * 0.9, 1e-12);
  EXPECT_NEAR(nearer[0].panel_height_m, 0.98 * 0.9, 1e-12);
  // and the tilt's N stays: σ·s over an extent L·s, as it was.
  EXPECT_NEAR(nearer[0].normal_tilt_deg, 20, 1e-9);
  c.injected = {{"disparity_offset", {{"delta_px", 0.5}}, ""}};
  const double near = 60 / (60 / 16.0 + 0.5) / 16;  // 14.1 m of 16
  const records::PanelMetrics near_row = InjectIntoRealTable({m}, c, 60, 1.0)[0];
  EXPECT_NEAR(near_row.panel_width_m, 1.02 * near, 1e-12);
  EXPECT_NEAR(std::tan(near_row.normal_tilt_deg * M_PI / 180),
              std::tan(20 * M_PI / 180) * near, 1e-9);  // σ·r² over an extent L·r
  c.injected = {{"disparity_offset", {{"delta_px", -4}}, ""}};  // 3.75 px at 16 m
  EXPECT_THROW(InjectIntoRealTable({m}, c, 60, 1.0), std::invalid_argument);
  c.injected = {{"panel_tilt", {{"yaw_deg", 10}}, ""}};
  EXPECT_THROW(InjectIntoRealTable({m}, c, 60, 1.0), std::invalid_argument);
  // plane_std grows no further than a uniform spread over the panel's shorter side (s/√12): the
  // plane fit's smallest axis then lies in the panel's plane. The row's measured extent (0.98 m),
  // else the panel's known side; a row already beyond keeps its value.
  c.injected = {{"disparity_offset", {{"delta_px", -0.5}}, ""}};
  records::PanelMetrics wide = m, unmeasured = m, beyond = m;
  wide.plane_std_m = 0.25;  // 0.333 m by (Z'/Z)²
  unmeasured.plane_std_m = 0.25;
  unmeasured.panel_width_m = unmeasured.panel_height_m = NAN;
  beyond.plane_std_m = 0.3;
  const auto capped = InjectIntoRealTable({wide, unmeasured, beyond}, c, 60, 0.9);
  EXPECT_NEAR(capped[0].plane_std_m, 0.98 / std::sqrt(12.0), 1e-12);
  EXPECT_NEAR(capped[1].plane_std_m, 0.9 / std::sqrt(12.0), 1e-12);
  EXPECT_EQ(capped[2].plane_std_m, 0.3);
  // The cases' sizes: 1.5 and 0.5 times the table's limit on the over-reading side; an effect
  // with no limit inside its grid that way is left out.
  DetectionLimits limits;
  const DetectionLimit offset = OffsetLimit();
  DetectionLimit scale = offset;
  scale.effect = "depth_scale";
  scale.param = "scale_rel";
  scale.size = {-0.08, NAN};
  scale.far_m = {-1.2, 1.8};
  limits.effects = {offset, scale};
  const std::vector<WithheldCase> cases = RealInjectionCases(limits, "t");
  ASSERT_EQ(cases.size(), 2u);
  EXPECT_EQ(cases[0].name, "t + disparity_offset (1.5 × its limit)");
  EXPECT_NEAR(cases[0].injected[0].params.at("delta_px"), -0.98, 1e-12);
  EXPECT_FALSE(cases[0].may_go_unseen);
  EXPECT_NEAR(cases[1].injected[0].params.at("delta_px"), -0.327, 1e-12);
  EXPECT_TRUE(cases[1].may_go_unseen && cases[1].on_real);
  EXPECT_TRUE(IsRealInjectionCase(cases[1].name));
  EXPECT_FALSE(IsRealInjectionCase("disparity_offset large"));
  // Other multiples (diagnose_gap --inject-times): named by the multiple, unseen only below 1.
  const std::vector<WithheldCase> more = RealInjectionCases(limits, "t", {1, 2.25});
  ASSERT_EQ(more.size(), 2u);
  EXPECT_EQ(more[0].name, "t + disparity_offset (1 × its limit)");
  EXPECT_NEAR(more[0].injected[0].params.at("delta_px"), -0.653, 1e-12);
  EXPECT_FALSE(more[0].may_go_unseen);
  EXPECT_EQ(more[1].name, "t + disparity_offset (2.25 × its limit)");
  EXPECT_NEAR(more[1].injected[0].params.at("delta_px"), -1.47, 1e-12);
  EXPECT_TRUE(IsRealInjectionCase(more[1].name));
  for (const char* name : {"t + disparity_offset (0 × its limit)",
                           "t + disparity_offset (x × its limit)",
                           "t + disparity_offset ( × its limit)",
                           "t + disparity_offset (11 × its limit)", "(2 × its limit)"})
    EXPECT_FALSE(IsRealInjectionCase(name)) << name;
  EXPECT_THROW(RealInjectionCases(limits, "t", {0}), std::invalid_argument);
}

// Outside the registry on a real table: at each multiple from 1 on, the offset's median at the
// table's farthest distance as a far over-read ∝ D² in the median and the mean alone (the
// spreads, the valid share and the window as they were): the offset's over-read without what
// an offset does to the spreads. Below 1 × no case asks it to be seen.
TEST(RealTable, AnOverReadOutsideTheRegistryIsTheOffsetsMedianWithoutItsSpreads) {
  DetectionLimits limits;
  limits.far_distance_m = 16;
  const DetectionLimit offset = OffsetLimit();
  limits.effects = {offset};
  const std::vector<WithheldCase> cases = RealInjectionCases(limits, "t");
  ASSERT_EQ(cases.size(), 3u);
  const WithheldCase& far = cases[2];
  EXPECT_EQ(far.name, "t + far over-read ∝ D², outside (1.5 × its limit)");
  EXPECT_TRUE(IsRealInjectionCase(far.name));
  EXPECT_TRUE(far.on_real && far.injected.empty() && !far.may_go_unseen);
  EXPECT_EQ(far.outside.kind, OutsideEffect::kFarOverRead);
  EXPECT_NEAR(far.outside.coef, 1.72, 1e-12);  // 1.5 × 2.93 m / 1.6², 3 digits
  EXPECT_EQ(far.outside.from_distance_m, 8);
  const std::vector<std::string> names = RealInjectionCaseNames("t", {1.5, 0.5});
  EXPECT_NE(std::find(names.begin(), names.end(), far.name), names.end());
  EXPECT_EQ(RealInjectionCases(limits, "t", {0.5}).size(), 1u);
  const records::PanelMetrics row = RowAt16();
  records::PanelMetrics unmeasured = row;
  unmeasured.median_m = unmeasured.mean_m = NAN;
  const auto rows = InjectIntoRealTable({row, unmeasured}, far, 60, 1);
  EXPECT_NEAR(rows[0].median_m, 16 + 1.72 * 2.56, 1e-9);
  EXPECT_NEAR(rows[0].mean_m - rows[0].median_m, 0.1, 1e-9);
  EXPECT_EQ(rows[0].plane_std_m, row.plane_std_m);
  EXPECT_EQ(rows[0].temporal_std_m, row.temporal_std_m);
  EXPECT_EQ(rows[0].valid_pct, row.valid_pct);
  EXPECT_EQ(rows[0].panel_width_m, row.panel_width_m);
  EXPECT_EQ(rows[0].normal_tilt_deg, row.normal_tilt_deg);
  EXPECT_TRUE(std::isnan(rows[1].median_m));
}

// One test point read far on a real table: the table's second distance and angle in its first
// light, 1.5 times the smallest departure its own placement test flags there (the critical z of
// 0.05 over its test points, Bonferroni, times the median's law at that distance); none below 1.
TEST(RealTable, OneTestPointReadFarIsSizedByTheTablesOwnPlacementLaw) {
  DiagnoseResult reference;
  reference.design.metrics = {kMedianBias, kPlaneStd};
  PlacementEstimate& pe = reference.placement;
  for (const char* light : {"daylight", "sunset"})
    for (double d : {4.0, 8.0, 16.0})
      for (double a : {0.0, 10.0, 35.0}) {
        pe.point_light.push_back(light);
        pe.point_distance_m.push_back(d);
        pe.point_angle_deg.push_back(a);
      }
  pe.num_points = static_cast<int>(pe.point_light.size());
  pe.point = {9, 0};  // the first row's test point: sunset, 4 m, 0°
  pe.a = {0.1, 0.02};
  pe.b = {0.05, 0};
  const std::vector<WithheldCase> cases = RealPointStepCases(reference, "t", {1.5, 0.5}, 0.05);
  ASSERT_EQ(cases.size(), 1u);
  const WithheldCase& c = cases[0];
  EXPECT_EQ(c.name, "t + one test point read far, outside (1.5 × its limit)");
  EXPECT_TRUE(IsRealInjectionCase(c.name) && c.on_real && c.injected.empty());
  EXPECT_EQ(c.outside.kind, OutsideEffect::kPointStep);
  EXPECT_EQ(c.outside.light, "sunset");
  EXPECT_EQ(c.outside.distance_m, 8);
  EXPECT_EQ(c.outside.angle_deg, 10);
  // 1.5 × 2.99 (two-sided, 0.05 / 18) × (0.1 + 0.05 · 8) m = 2.24 m.
  EXPECT_NEAR(c.outside.coef, 1.5 * TwoSidedCritical(0.05 / 18) * 0.5, 0.005);
  EXPECT_NEAR(c.outside.coef, 2.24, 0.01);
  const std::vector<std::string> names = RealInjectionCaseNames("t", {1.5});
  EXPECT_NE(std::find(names.begin(), names.end(), c.name), names.end());
  // Without a median, or without its test point: none.
  DiagnoseResult no_median = reference;
  no_median.design.metrics = {kPlaneStd};
  EXPECT_TRUE(RealPointStepCases(no_median, "t", {1.5}, 0.05).empty());
  DiagnoseResult one_point = reference;
  one_point.placement.num_points = 1;
  EXPECT_TRUE(RealPointStepCases(one_point, "t", {1.5}, 0.05).empty());
  DiagnoseResult no_cells = reference;
  no_cells.placement.point.clear();
  EXPECT_TRUE(RealPointStepCases(no_cells, "t", {1.5}, 0.05).empty());
}

// The map against the physics it stands for: the simulator's own table without effect, mapped by
// InjectIntoRealTable, and the simulator's table of the same effect (the renderer's disparities
// moved, every pixel quantized and the panel's window laid on the measured plane anew) agree
// within the tables' noise. Two seeds (5 and 6, 256 recordings of the article's protocol, 10
// frames), pooled per distance over the presets and seeds. The tilt, a panel facing the camera's
// plane-fit error, is compared by its RMS tangent, about 6 % of noise over 128 recordings (tan²
// of a normal's error in two directions scatters as its mean): 0.89 at 16 m under both
// effects, 0.97-1.04 nearer. Its map by Z'/Z (the plane's turn it used to take) gives 0.68 at
// 16 m under the offset, and 1 under the scale 0.73. mean - median is left out: the region's
// decision trims the tail of a far, noisy panel, and the map's (Z'/Z)^2 reads it about twice
// the simulator's at 16 m HD (docs/gap/cases.md, The tilt of an injected real row).
TEST(RealTable, AnInjectionOfTheSimulatorsTableIsItsSimulationOfTheEffect) {
  const sim::SimParams base = Base();
  const double fb = base.sensor.focal_px() * base.sensor.baseline_m;
  sim::MetricsParams mp;
  mp.frames = 10;
  mp.threads = 2;
  // plane_std's ceiling: a uniform spread over the panel's side, 1 m / √12 (MapRow). Near it
  // the simulator's spread stops short of it (0.26-0.28 m at 16 m 0°, less at wider angles),
  // where the map still lets it grow: the rows of the simulator's daylight HA and every HD at
  // 16 m read 3-5 % more mapped than simulated. The comparison keeps the spreads below half of
  // it, where the map reads 0.999-1.007 of the simulation but 1.023 at 16 m under the offset
  // (the region's decision, which leaves out pixels far off the plane, trims a far panel's
  // spread): within 3 %.
  constexpr double kUnsaturated = 0.5 / std::sqrt(12.0);
  const std::vector<std::pair<std::string, double>> effects{{"disparity_offset", -0.5},
                                                            {"depth_scale", 0.1}};
  for (const auto& [effect, size] : effects) {
    SCOPED_TRACE(effect);
    // [distance] sums over both seeds: tan² of the tilt (mapped, simulated), plane_std where it
    // is below half its ceiling (mapped, simulated), temporal_std, the median, and the count.
    std::map<double, std::array<double, 9>> sums;
    for (std::uint64_t seed : {5u, 6u}) {
      sim::SimParams p = base, q = base;
      p.seed = q.seed = seed;
      std::string why;
      const std::string param = effect == "depth_scale" ? "scale_rel" : "delta_px";
      ASSERT_TRUE(sim::BuildDepartures({{effect, {{param, size}}}}, &q.departures, &why)) << why;
      std::vector<records::PanelMetrics> plain, moved;
      for (const auto& r : sim::SimulateProtocolMetrics(p, mp)) plain.push_back(r.metrics);
      for (const auto& r : sim::SimulateProtocolMetrics(q, mp)) moved.push_back(r.metrics);
      WithheldCase c;
      c.name = effect;
      c.injected = {{effect, {{param, size}}, ""}};
      const auto mapped = InjectIntoRealTable(plain, c, fb, 1.0);
      ASSERT_EQ(mapped.size(), moved.size());
      for (size_t i = 0; i < moved.size(); ++i) {
        const records::PanelMetrics &a = mapped[i], &b = moved[i];
        ASSERT_EQ(a.bag, b.bag);
        auto tan2 = [](double deg) { return std::pow(std::tan(deg * M_PI / 180), 2); };
        std::array<double, 9>& t = sums[a.distance_m];
        t[0] += tan2(a.normal_tilt_deg);
        t[1] += tan2(b.normal_tilt_deg);
        if (b.plane_std_m < kUnsaturated && plain[i].plane_std_m < kUnsaturated) {
          t[2] += a.plane_std_m;
          t[3] += b.plane_std_m;
        }
        t[4] += a.temporal_std_m;
        t[5] += b.temporal_std_m;
        t[6] += a.median_m;
        t[7] += b.median_m;
        t[8] += 1;
      }
    }
    for (const auto& [distance, t] : sums) {
      SCOPED_TRACE("distance " + std::to_string(distance));
      const double tilt = std::sqrt(t[0] / t[1]);
      std::printf("%s %g m: RMS tilt %.3f, plane_std %.4f, temporal_std %.4f, median %.5f\n",
                  effect.c_str(), distance, tilt, t[2] / t[3], t[4] / t[5], t[6] / t[7]);
      EXPECT_GT(tilt, 0.85);
      EXPECT_LT(tilt, 1.18);
      if (t[3] > 0) {
        EXPECT_NEAR(t[2] / t[3], 1, 0.03);
      }
      EXPECT_NEAR(t[4] / t[5], 1, 0.03);
      EXPECT_NEAR(t[6] / t[7], 1, 0.005);
    }
  }
}

// The article's 128 real rows with a disparity offset injected by its physics (lib/gap/cases.h,
// RealInjectionCases): the camera's own departures, placements and outliers are the table's
// background, which no simulator of ours made. At 1.5 times the over-reading limit the
// article's report gives (−0.979 px at seed 1, 4.9 m far at 16 m) it must be kept, alone, at
// its size; at half of it (−0.326 px) it may go unseen only where the limit published says so.
// While the folds' selections had to earn together whatever the table kept, the offset was
// dropped here: three folds of four selected it (its own part 20 % of their gap), and the fold
// holding 12 m out an edge mixing that lost 326 of its 769 simulated Σz², so the selections
// together removed 9.2 % of the calibrated gap (10 % needed). A guard of that rule at seed 1
// (kept at −0.908 px then; −1.05 px for −0.993 now, and at every seed of 1–5 since each variance
// component has its own dispersion: docs/gap/cases.md). At three times its limit (−1.99 px,
// beyond the offset's last node at −1.5 px) no registered size can take it. With one dispersion
// the offset alone earned and the pair was named "one of" (a range law at its grid's edge and a
// correlated rival that earns: lib/gap/README.md, Nested hold-out); with a dispersion per
// component, the scale was kept at its grid's edge (+20 %) with an interval to the registry's
// bound; with each spread's loading per scenario (placement.h, tau_cell) the outer folds split
// between the two again, and the pair is named "one of" them, nothing selected, with the far
// over-read named unexplained in the median. Once the region's noise was read on its interior
// (metrics/panel_pixels.h), the offset beyond its last node no longer fitted and the scale was
// kept alone at its grid's edge, its interval [−0.15, 0.5]: a range law at its grid's edge is
// not kept, with a rival or without (lib/gap/diagnose.cpp), and the folds' split names the pair.
TEST(Article, AnOffsetInjectedBeyondItsLimitIsKept) {
  std::vector<records::PanelMetrics> rows =
      io::ReadMetricsCsv(DEPTHBIAS_SOURCE_DIR "/config/data/paper_d455_outdoor.csv");
  const sim::SimParams base = Base();
  ScreenRows(DesignRulesOf(base.sensor), &rows);
  DiagnoseParams params;
  params.simulate.threads = 2;
  const std::vector<CaseOutcome> all = RunRealInjectionCases(
      base, rows, "article", params,
      {"article + disparity_offset (1.5 × its limit)", "article + disparity_offset (0.5 × its limit)",
       "article + disparity_offset (3 × its limit)"},
      {1.5, 0.5, 3});
  ASSERT_EQ(all.size(), 3u);
  // At 3 times its limit (−1.99 px, beyond the offset's last node at −1.5 px) no size is given:
  // nothing is selected, the pair the outer folds split between (the offset and the depth
  // scale, each at its grid's edge) is named "one of" them, and the far over-read is named
  // unexplained in the median, over 1 m at 16 m.
  const std::string& json = all[2].gap_json;
  auto from = [&](const char* key, size_t n) {
    const size_t at = json.find(key);
    return at == std::string::npos ? std::string("(no ") + key + ")" : json.substr(at, n);
  };
  EXPECT_TRUE(all[2].selected.empty()) << from("\"selected\"", 400);
  const size_t ambiguous = json.find("\"ambiguous\": [");
  ASSERT_NE(ambiguous, std::string::npos);
  bool pair = false;
  for (size_t at = json.find("\"one_of\": [", ambiguous);
       at != std::string::npos && at < json.find("\"not_kept\"", ambiguous);
       at = json.find("\"one_of\": [", at + 1)) {
    const std::string names = json.substr(at, json.find(']', at) - at);
    pair = pair || (names.find("\"disparity_offset\"") != std::string::npos &&
                    names.find("\"depth_scale\"") != std::string::npos);
  }
  EXPECT_TRUE(pair) << from("\"ambiguous\"", 1200);
  const size_t open = json.find("\"unexplained\": [");
  ASSERT_NE(open, std::string::npos);
  const size_t median = json.find("\"metric\": \"median_bias_m\"", open);
  ASSERT_NE(median, std::string::npos) << json.substr(open, 600);
  const size_t far = json.find("\"size_at_far_end\": ", median);
  ASSERT_NE(far, std::string::npos) << json.substr(median, 400);
  EXPECT_GE(std::strtod(json.c_str() + far + 19, nullptr), 1.0) << json.substr(median, 400);
  const std::vector<CaseOutcome> outcomes(all.begin(), all.begin() + 2);
  for (const CaseOutcome& o : outcomes) {
    std::string recovered;
    for (const auto& [effect, size] : o.recovered) recovered += effect + ": " + size + "; ";
    if (o.truth.may_go_unseen) {
      EXPECT_TRUE(o.pass) << o.truth.name << ": " << o.why << "\n" << recovered;
    } else {
      // At 1.5 times its limit the offset is kept at its size; its selection, simulated,
      // removes 70 % of the injected gap at 4 of 5 seeds of the suite (docs/gap/cases.md, Over
      // five seeds), at this seed 61.4 % since the plane's spread is smoothed as a window
      // metric (at seed 4 the other way round).
      EXPECT_LE(o.max_rel_error, 0.2) << recovered;
      EXPECT_GE(o.shrink_simulated_pct, 60.0) << o.why;
    }
    if (!o.truth.may_go_unseen) {
      EXPECT_EQ(o.selected, std::vector<std::string>{"disparity_offset"}) << recovered;
    }
    std::printf("%s: %s\n", o.truth.name.c_str(), recovered.c_str());
  }
}

// At seeds 2 and 3 the same offset (−0.93 and −0.97 px there) is kept, at its size within 20 %.
// With one dispersion for a metric's two variance components (every residual over √(σ² + τ²),
// one robust scale: 5.4 for the median on the injected table, whose recordings spread about
// their test point's mean 26 times the twins' variance) the placement law was widened by as
// much, and the offset's evidence, which lies in the test points' means, with it: at seed 3 the
// outer folds split between the offset and a depth scale of +19.7 % and the pair was named "one
// of"; at seed 2 three folds of four chose the offset but their selections removed 8.0 % of the
// calibrated gap (10 % needed), and the gap was reported unexplained (∝ D², 5.5 m at 16 m).
// Each component now has its own dispersion (select.h, Dispersion).
TEST(Article, AnOffsetOneDispersionLostIsKeptWhereTheTestPointsMeansShowIt) {
  std::vector<records::PanelMetrics> rows =
      io::ReadMetricsCsv(DEPTHBIAS_SOURCE_DIR "/config/data/paper_d455_outdoor.csv");
  sim::SimParams base = Base();
  ScreenRows(DesignRulesOf(base.sensor), &rows);
  DiagnoseParams params;
  params.simulate.threads = 2;
  for (const int seed : {3, 2}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    base.seed = seed;
    const std::vector<CaseOutcome> outcomes = RunRealInjectionCases(
        base, rows, "article", params, {"article + disparity_offset (1.5 × its limit)"});
    ASSERT_EQ(outcomes.size(), 1u);
    const CaseOutcome& o = outcomes[0];
    std::string recovered;
    for (const auto& [effect, size] : o.recovered) recovered += effect + ": " + size + "; ";
    EXPECT_EQ(o.selected, std::vector<std::string>{"disparity_offset"}) << recovered;
    EXPECT_TRUE(o.pass) << o.why << "\n" << recovered;
    std::printf("seed %d: %s\n", seed, recovered.c_str());
  }
}

}  // namespace
}  // namespace depthbias::gap
