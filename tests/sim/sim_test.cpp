// The simulated D455: repeatability, agreement of whole frames with the metrics-only path, the
// base model against its formulas, and every effect against its signature.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <set>

#include "common/select.h"
#include "sim/effects.h"
#include "sim/sim_metrics.h"
#include "sim/stereo_sim.h"

namespace depthbias::sim {
namespace {

constexpr double kFB = 640.0 * 0.095;  // f·B [px·m]

SimParams Base(double sigma_d_px = 0.1, double invalid_prob = 0.2, int frames = 10) {
  SimParams p;
  p.protocol.frames = frames;
  p.sensor.fallback.sigma_d_px = sigma_d_px;
  p.sensor.fallback.invalid_prob = invalid_prob;
  p.seed = 7;
  return p;
}

Cell MakeCell(double distance_m, double angle_deg, const std::string& preset = "HA",
              bool emitter = false, const std::string& light = "daylight") {
  Cell c;
  c.distance_m = distance_m;
  c.angle_deg = angle_deg;
  c.preset = preset;
  c.emitter_on = emitter;
  c.light = light;
  c.name = CellName(c);
  return c;
}

// Metrics with the edge band (1 px) outside the region unless a margin is given.
records::PanelMetrics Metrics(const SimParams& p, const Cell& c, double margin_px = 3) {
  MetricsParams mp;
  mp.region_margin_px = margin_px;
  const CellMetricsResult r = SimulateMetrics(p, c, mp);
  EXPECT_TRUE(r.metrics.ok()) << c.name << ": " << r.metrics.message;
  return r.metrics;
}

SimParams With(SimParams p, const std::vector<EffectSpec>& effects) {
  std::string why;
  EXPECT_TRUE(BuildDepartures(effects, &p.departures, &why)) << why;
  return p;
}

// Depth step of one disparity quantum at Z: ΔZ ≈ Z²·step/(f·B).
double QuantumM(double z) { return z * z / kFB / 32.0; }

TEST(StereoSim, SameSeedSameFramesOtherSeedOthers) {
  SimParams p = Base();
  const Cell c = MakeCell(8, 10);
  records::DepthFrame a, b, other;
  StereoSim(p, c).Render(3, &a);
  StereoSim(p, c).Render(3, &b);
  p.seed = 8;
  StereoSim(p, c).Render(3, &other);
  EXPECT_EQ(a.counts, b.counts);
  EXPECT_NE(a.counts, other.counts);
  EXPECT_EQ(a.width, 1280);
  EXPECT_EQ(a.height, 720);
  EXPECT_EQ(a.frame_number, 4u);
}

TEST(StereoSim, WholeFramesAndTheFootprintGiveTheSamePixels) {
  const SimParams p = With(Base(), {{"edge_mixing", {{"width_px", 4}}}});
  const Cell c = MakeCell(12, 20);
  const StereoSim whole(p, c);
  const PixelList panel = whole.PanelPixels(3);
  ASSERT_GT(panel.size(), 1000u);
  // A window around a few panel pixels, with room for the edge and mixing filters.
  const int i0 = panel.window[panel.size() / 2];
  const Window window{i0 % 1280 - 60, i0 / 1280 - 60, 120, 120};
  const StereoSim part(p, c, window);
  const PixelList part_panel = part.PanelPixels(3);
  ASSERT_GT(part_panel.size(), 100u);
  records::DepthFrame frame;
  std::vector<std::uint16_t> counts;
  for (int k : {0, 5}) {
    whole.Render(k, &frame);
    part.RenderPixels(k, part_panel, &counts);
    for (size_t i = 0; i < part_panel.size(); ++i) {
      const int u = window.u0 + part_panel.window[i] % window.width;
      const int v = window.v0 + part_panel.window[i] / window.width;
      ASSERT_EQ(counts[i], frame.at(u, v)) << "pixel " << u << "," << v << " frame " << k;
    }
  }
}

TEST(StereoSim, MetricsOnlyEqualsMetricsOfRenderedFrames) {
  const SimParams p = Base(0.1, 0.3, 6);
  const Cell c = MakeCell(16, 35);
  const StereoSim sim(p, c);
  // The region the metrics-only path draws: the panel's size on the plane it measured.
  MetricsParams mp;
  mp.region_margin_px = 3;
  const CellMetricsResult measured = SimulateMetrics(p, c, mp);
  const PixelList region = sim.RegionPixels(3, nullptr, &measured.window);
  std::vector<double> z;
  size_t total = 0;
  records::DepthFrame frame;
  for (int k = 0; k < p.protocol.frames; ++k) {
    sim.Render(k, &frame);
    for (int i : region.window) {
      ++total;
      if (frame.counts[i]) z.push_back(frame.counts[i] * 0.001);
    }
  }
  const records::PanelMetrics m = Metrics(p, c);
  EXPECT_NEAR(m.valid_pct, 100.0 * z.size() / total, 1e-9);
  std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
  EXPECT_NEAR(m.median_m, z[z.size() / 2], 0.0011);
  EXPECT_EQ(m.region_px, static_cast<double>(region.size()));
}

TEST(StereoSim, BaseModelFollowsItsFormulas) {
  const double sigma = 0.05, p_hole = 0.25;
  const SimParams p = Base(sigma, p_hole, 10);
  for (double d : {4.0, 8.0, 12.0}) {
    const records::PanelMetrics m = Metrics(p, MakeCell(d, 0));
    // Median at the true depth within one quantum; plane_std = Z²/(f·B)·√(σ² + step²/12).
    EXPECT_NEAR(m.median_m, d, QuantumM(d) + 0.001) << d;
    const double expected_std = d * d / kFB * std::sqrt(sigma * sigma + 1.0 / (12 * 32 * 32));
    EXPECT_NEAR(m.plane_std_m / expected_std, 1.0, 0.05) << d;
    // Holes: p on the panel (reference texture), the edge band eroded away by the margin.
    EXPECT_NEAR(m.hole_rate_pct, 100 * p_hole, 1.0) << d;
    EXPECT_NEAR(m.subpixel_rms_px, std::sqrt(sigma * sigma + 1.0 / (12 * 32 * 32)), 0.01) << d;
    EXPECT_NEAR(m.normal_tilt_deg, 0.0, 2.0) << d;
  }
}

TEST(StereoSim, RangeMeaningPutsOffAxisPanelsAtRangeCosAlpha) {
  SimParams p = Base(0.02, 0.1, 4);
  const records::PanelMetrics by_range = Metrics(p, MakeCell(12, 35));
  EXPECT_NEAR(by_range.median_m, 12 * std::cos(35 * M_PI / 180), QuantumM(12) + 0.001);
  EXPECT_NEAR(by_range.azimuth_deg, 35.0, 0.5);
  p.protocol.distance_is = DistanceIs::kDepth;
  const records::PanelMetrics by_depth = Metrics(p, MakeCell(12, 35));
  EXPECT_NEAR(by_depth.median_m, 12.0, QuantumM(12) + 0.001);
}

TEST(StereoSim, EmitterAndEdgesChangeHolesTheWayTheModelSays) {
  SimParams p = Base(0.1, 0.5, 10);
  // The emitter adds texture at short range: fewer holes at 4 m, almost none less at 16 m.
  const double off4 = Metrics(p, MakeCell(4, 0, "HA", false)).hole_rate_pct;
  const double on4 = Metrics(p, MakeCell(4, 0, "HA", true)).hole_rate_pct;
  const double on16 = Metrics(p, MakeCell(16, 0, "HA", true)).hole_rate_pct;
  const double t = p.sensor.emitter_texture;  // (reach/Z)² = 1 at 4 m
  EXPECT_NEAR(on4, 100.0 / (1 + std::exp(p.sensor.texture_slope * t)), 1.0);
  EXPECT_NEAR(off4, 50.0, 1.0);
  EXPECT_GT(on16, on4);
  // Depth edges: the far side (the ground just below the panel's lower edge) gets holes with
  // probability ≥ edge_invalid_prob over edge_band_px rows; the panel's own edge pixels do not.
  p.sensor.fallback.invalid_prob = 0.1;
  const Cell c = MakeCell(8, 0);
  const StereoSim sim(p, c);
  const PixelList panel = sim.PanelPixels(0);
  int bottom = 0, left = 1280, right = 0;
  for (int i : panel.window) {
    bottom = std::max(bottom, i / 1280);
    left = std::min(left, i % 1280);
    right = std::max(right, i % 1280);
  }
  std::vector<double> holes(9, 0.0), seen(9, 0.0);  // rows bottom−1 … bottom+7
  records::DepthFrame frame;
  for (int k = 0; k < 10; ++k) {
    sim.Render(k, &frame);
    for (int r = 0; r < 9; ++r)
      for (int u = left + 5; u < right - 5; ++u) {
        ++seen[r];
        holes[r] += frame.at(u, bottom - 1 + r) == 0;
      }
  }
  for (int r = 0; r < 9; ++r) holes[r] /= seen[r];
  EXPECT_NEAR(holes[0], 0.1, 0.03);  // the panel's last two rows
  EXPECT_NEAR(holes[1], 0.1, 0.03);
  for (int r = 2; r <= 4; ++r) EXPECT_NEAR(holes[r], 0.5, 0.06) << r;  // ground: 3 rows of band
  for (int r = 5; r <= 8; ++r) EXPECT_LT(holes[r], 0.05) << r;  // textured ground further down
  EXPECT_EQ(p.sensor.edge_band_px, 3);
}

TEST(StereoSim, SmoothInItsParameters) {
  // Common random numbers: a small change of σ_d gives a small change of plane_std.
  const Cell c = MakeCell(8, 10);
  const double a = Metrics(Base(0.100), c).plane_std_m;
  const double b = Metrics(Base(0.101), c).plane_std_m;
  EXPECT_GT(b, a);
  EXPECT_LT(b / a - 1, 0.03);
}

TEST(StereoSim, DitheredQuantizationTakesThePhaseOutOfTheMedian) {
  // An offset swept over one subpixel step at 16 m, where a step of disparity is 0.13 m of
  // depth: on the camera's fixed lattice the median moves by whole steps (its departure from
  // f·B/(f·B/Z + δ) scatters by about step/√12 over the sweep); with each pixel on a lattice
  // of its own phase it follows the formula within a fraction of that, the spreads (over the
  // region, and of a pixel over time) left within 2 %.
  const double z = 16, quantum = QuantumM(z);
  const Cell c = MakeCell(z, 0);
  double ss[2] = {0, 0}, sum[2] = {0, 0};
  const int n = 16;
  for (int dither = 0; dither < 2; ++dither)
    for (int j = 0; j < n; ++j) {
      const double delta = -0.25 + j / 32.0 / n;
      SimParams p = With(Base(0.07, 0.2, 16), {{"disparity_offset", {{"delta_px", delta}}}});
      p.dither_quantization = dither == 1;
      const double e = Metrics(p, c).median_m - kFB / (kFB / z + delta);
      ss[dither] += e * e;
      sum[dither] += e;
    }
  const double rms_fixed = std::sqrt(ss[0] / n), rms_dithered = std::sqrt(ss[1] / n);
  EXPECT_GT(rms_fixed, 0.5 * quantum / std::sqrt(12.0));
  EXPECT_LT(rms_dithered, 0.25 * quantum / std::sqrt(12.0));
  EXPECT_LT(std::fabs(sum[1] / n), 0.1 * quantum);

  SimParams fixed = Base(0.07, 0.2, 16), dithered = fixed;
  dithered.dither_quantization = true;
  for (double d : {4.0, 8.0, 16.0}) {
    const records::PanelMetrics a = Metrics(fixed, MakeCell(d, 20)),
                                b = Metrics(dithered, MakeCell(d, 20));
    EXPECT_NEAR(b.plane_std_m / a.plane_std_m, 1.0, 0.02) << d;
    EXPECT_NEAR(b.temporal_std_m / a.temporal_std_m, 1.0, 0.02) << d;
    EXPECT_NEAR(b.valid_pct, a.valid_pct, 0.5) << d;
  }
}

// --- Effects: each moves the metrics as its formula says. ---

TEST(Effects, DisparityOffsetShiftsTheMedianByMinusDeltaZSquaredOverFB) {
  const SimParams base = Base(0.05, 0.2, 10);
  const double delta = 0.2;
  const SimParams on = With(base, {{"disparity_offset", {{"delta_px", delta}}}});
  for (double d : {4.0, 8.0, 16.0}) {
    const Cell c = MakeCell(d, 0);
    const double shift = Metrics(on, c).median_m - Metrics(base, c).median_m;
    const double expected = kFB / (kFB / d + delta) - d;  // exact: f·B/(f·B/Z + δ) − Z
    EXPECT_NEAR(shift, expected, QuantumM(d) + 0.002) << d;
    EXPECT_NEAR(expected, -delta * d * d / kFB, 0.15 * std::fabs(expected)) << d;
  }
}

TEST(Effects, DepthScaleShiftsTheMedianBySZ) {
  const SimParams base = Base(0.05, 0.2, 8);
  const SimParams on = With(base, {{"depth_scale", {{"scale_rel", 0.02}}}});
  for (double d : {4.0, 12.0}) {
    const Cell c = MakeCell(d, 10);
    const records::PanelMetrics m0 = Metrics(base, c), m1 = Metrics(on, c);
    EXPECT_NEAR(m1.median_m - m0.median_m, 0.02 * m0.median_m, 0.002) << d;
    // Scaled like the depths, up to the 1 mm rounding of the counts (levels 8.2 mm apart at
    // 4 m come out 8 or 9 mm apart: a few percent there).
    EXPECT_NEAR(m1.plane_std_m / m0.plane_std_m, 1.02, d < 5 ? 0.04 : 0.01) << d;
  }
}

TEST(Effects, RangeVsDepthMovesOffAxisPanelsByROneMinusCos) {
  const SimParams base = Base(0.03, 0.2, 6);  // distance_is: range
  const SimParams on = With(base, {{"range_vs_depth", {{"weight", 1.0}}}});
  for (double a : {0.0, 20.0, 35.0}) {
    const Cell c = MakeCell(8, a);
    const double shift = Metrics(on, c).median_m - Metrics(base, c).median_m;
    EXPECT_NEAR(shift, 8 * (1 - std::cos(a * M_PI / 180)), QuantumM(8) + 0.002) << a;
  }
}

TEST(Effects, RadialResidualBiasGrowsWithTanSquaredAlpha) {
  const SimParams base = Base(0.03, 0.2, 6);
  const double k = 0.2;
  const SimParams on = With(base, {{"radial_disparity_residual", {{"k_px", k}}}});
  for (double a : {0.0, 20.0, 35.0}) {
    const Cell c = MakeCell(8, a);
    const records::PanelMetrics m0 = Metrics(base, c);
    const double shift = Metrics(on, c).median_m - m0.median_m;
    const double z = m0.median_m, t = std::tan(a * M_PI / 180);
    const double expected = -k * t * t * z * z / kFB;
    EXPECT_NEAR(shift, expected, 0.1 * std::fabs(expected) + QuantumM(z) + 0.002) << a;
  }
}

TEST(Effects, EdgeMixingPullsTheMeanAndWorsensWithDistance) {
  const SimParams base = Base(0.02, 0.1, 8);
  const SimParams on = With(base, {{"edge_mixing", {{"width_px", 4}, {"strength", 0.6}}}});
  // The region is decided from the frames (metrics::DecidePanelPixels, as panel_extract does): a
  // mixed edge pixel lies far enough off the panel's plane to be left out, so the metrics keep
  // the panel's own pixels (median and mean hold) and the region loses the mixed border, a
  // larger share of it the smaller the panel's image.
  double kept_before = 1.0;
  for (double d : {4.0, 8.0, 16.0}) {
    const Cell c = MakeCell(d, 0);
    const records::PanelMetrics m0 = Metrics(base, c, 1), m1 = Metrics(on, c, 1);
    EXPECT_NEAR(m1.median_m, m0.median_m, QuantumM(d) + 0.002) << d;
    EXPECT_NEAR(m1.mean_m, m0.mean_m, 0.01 * d / 4) << d;
    const double kept = m1.region_px / m0.region_px;
    EXPECT_LT(kept, kept_before) << d;
    kept_before = kept;
  }
  EXPECT_LT(kept_before, 0.85);  // at 16 m
  // Kept in the region (a decision that leaves no pixel out: the metrics of every region pixel),
  // the mixed pixels pull the mean behind the median.
  const Cell far = MakeCell(16, 0);
  MetricsParams all;
  all.region_margin_px = 1;
  all.region.plane_distance_m = 100;
  const records::PanelMetrics k0 = SimulateMetrics(base, far, all).metrics;
  const records::PanelMetrics k1 = SimulateMetrics(on, far, all).metrics;
  EXPECT_GT(k1.mean_m - k1.median_m, k0.mean_m - k0.median_m + 0.01 * 16 / 4);
  // A margin wider than the mixing width removes it from the region.
  const Cell c = MakeCell(8, 0);
  EXPECT_NEAR(Metrics(on, c, 6).mean_m, Metrics(base, c, 6).mean_m, 0.002);
}

// The region's decision has one answer wherever the panel stands: a mixed border is judged
// against the noise of the panel's interior, never against a scatter it widens itself. Read over
// the whole region, the same border was left out at some placements and kept at others a
// centimetre or two further (at 16.02 m of a calibrated HA sensor: tilt 14°, mean − median
// 0.65 m, against 1.5° and 0.07 m at 16.00 m), so that a camera's edge mixing read as a step in
// where its panel happened to stand.
TEST(Effects, EdgeMixingIsJudgedAlikeAtEveryPlacement) {
  const SimParams base = Base(0.07, 0.7, 10);
  const SimParams on = With(base, {{"edge_mixing", {{"width_px", 3}, {"strength", 0.5}}}});
  int left_out_everywhere = 0, placements = 0;
  for (double d = 15.84; d < 16.17; d += 0.03, ++placements) {
    const Cell c = MakeCell(d, 0);
    const records::PanelMetrics m0 = Metrics(base, c, 0), m1 = Metrics(on, c, 0);
    EXPECT_LT(std::fabs((m1.mean_m - m1.median_m) - (m0.mean_m - m0.median_m)), 0.15) << d;
    EXPECT_LT(m1.normal_tilt_deg, m0.normal_tilt_deg + 5) << d;
    left_out_everywhere += m1.region_px < m0.region_px;  // the border's pixels are left out
  }
  EXPECT_EQ(left_out_everywhere, placements);
}

TEST(Effects, NoiseGainMultipliesPlaneStd) {
  const SimParams base = Base(0.08, 0.2, 10);
  const SimParams on = With(base, {{"disparity_noise_gain", {{"gain", 2.0}}}});
  const double q2 = 1.0 / (12 * 32 * 32);
  const double expected = std::sqrt((4 * 0.08 * 0.08 + q2) / (0.08 * 0.08 + q2));
  for (double d : {4.0, 8.0}) {  // σ_Z below the panel's size: the plane fit stays well posed
    const Cell c = MakeCell(d, 10);
    const records::PanelMetrics m0 = Metrics(base, c), m1 = Metrics(on, c);
    EXPECT_NEAR(m1.plane_std_m / m0.plane_std_m, expected, 0.05 * expected) << d;
    EXPECT_NEAR(m1.temporal_std_m / m0.temporal_std_m, expected, 0.1 * expected) << d;
    EXPECT_NEAR(m1.median_m, m0.median_m, QuantumM(d) + 0.002) << d;
  }
}

TEST(Effects, InvalidationGainMultipliesTheHoleOdds) {
  const double p0 = 0.2, g = 3.0;
  const SimParams base = Base(0.05, p0, 10);
  const SimParams on = With(base, {{"invalidation_gain", {{"gain", g}}}});
  const Cell c = MakeCell(8, 20);
  EXPECT_NEAR(Metrics(base, c).hole_rate_pct, 100 * p0, 1.0);
  EXPECT_NEAR(Metrics(on, c).hole_rate_pct, 100 * g * p0 / (1 - p0 + g * p0), 1.0);
  EXPECT_NEAR(Metrics(on, c).median_m, Metrics(base, c).median_m, 1e-9);
}

TEST(Effects, PanelTiltTurnsTheFittedNormal) {
  const SimParams base = Base(0.03, 0.2, 6);
  for (double yaw : {15.0, 30.0}) {
    const SimParams on = With(base, {{"panel_tilt", {{"yaw_deg", yaw}}}});
    const Cell c = MakeCell(4, 0);
    const records::PanelMetrics m0 = Metrics(base, c), m1 = Metrics(on, c);
    EXPECT_NEAR(m1.normal_tilt_deg, yaw, 1.0);
    // The far half covers fewer pixels: the median moves a little towards the near half.
    EXPECT_NEAR(m1.median_m, m0.median_m, 0.25 * std::sin(yaw * M_PI / 180));
    EXPECT_LT(m1.region_px, m0.region_px * std::cos(yaw * M_PI / 180) * 1.05);
  }
}

TEST(Effects, TemporalDriftShiftsTheMedianByTheMeanOffset) {
  const SimParams base = Base(0.03, 0.2, 30);
  const double rate = 0.2;  // px/s over 29 frame intervals at 30 fps
  const SimParams on = With(base, {{"temporal_drift", {{"rate_px_per_s", rate}}}});
  const double d = 8;
  const Cell c = MakeCell(d, 0);
  const records::PanelMetrics m0 = Metrics(base, c), m1 = Metrics(on, c);
  const double mean_offset = rate * 0.5 * 29.0 / 30.0;
  const double expected = -mean_offset * d * d / kFB;
  EXPECT_NEAR(m1.median_m - m0.median_m, expected, 0.15 * std::fabs(expected));
  EXPECT_GT(m1.temporal_std_m, 2 * m0.temporal_std_m);
}

TEST(Effects, NoEffectsIsTheBaseModel) {
  const SimParams base = Base();
  const SimParams none = With(base, {});
  const Cell c = MakeCell(12, 10);
  const records::PanelMetrics a = Metrics(base, c), b = Metrics(none, c);
  EXPECT_EQ(a.median_m, b.median_m);
  EXPECT_EQ(a.plane_std_m, b.plane_std_m);
}

TEST(Effects, RegistryRefusesUnknownNamesParametersAndBounds) {
  Departures d;
  std::string why;
  EXPECT_FALSE(BuildDepartures({{"lens_flare", {}}}, &d, &why));
  EXPECT_NE(why.find("lens_flare"), std::string::npos) << why;
  EXPECT_NE(why.find("disparity_offset"), std::string::npos) << why;  // lists the known ones
  EXPECT_FALSE(BuildDepartures({{"disparity_offset", {{"delta", 0.1}}}}, &d, &why));
  EXPECT_NE(why.find("delta"), std::string::npos) << why;
  EXPECT_FALSE(BuildDepartures({{"invalidation_gain", {{"gain", -1}}}}, &d, &why));
  EXPECT_NE(why.find("gain"), std::string::npos) << why;
  EXPECT_FALSE(BuildDepartures({{"disparity_offset", {{"delta_px", NAN}}}}, &d, &why));
  // Every registered effect is documented and builds with its defaults.
  for (const auto& e : EffectRegistry()) {
    EXPECT_FALSE(e.cause.empty()) << e.name;
    EXPECT_FALSE(e.signature.empty()) << e.name;
    EXPECT_FALSE(e.params.empty()) << e.name;
    EXPECT_TRUE(BuildDepartures({{e.name, {}}}, &d, &why)) << e.name << ": " << why;
  }
  EXPECT_EQ(EffectRegistry().size(), 11u);
}

TEST(StereoSim, RefusesInvalidParameters) {
  SimParams p = Base();
  p.sensor.baseline_m = -1;
  EXPECT_THROW(StereoSim(p, MakeCell(4, 0)), std::invalid_argument);
  p = Base();
  p.protocol.frames = 0;
  EXPECT_THROW(SimulateMetrics(p, MakeCell(4, 0)), std::invalid_argument);
  MetricsParams mp;
  mp.region_margin_px = -1;
  EXPECT_THROW(SimulateMetrics(Base(), MakeCell(4, 0), mp), std::invalid_argument);
}

// Widths of region_spill simulated together (one sensor, footprint and plane a recording) give
// each width's metrics alone, bit for bit, in any order, a width twice and width 0 (the decided
// region) among them.
TEST(StereoSim, SpillWidthsTogetherAreEachWidthAlone) {
  const SimParams base = Base(0.1, 0.2, 4);
  using M = records::PanelMetrics;
  constexpr double M::*kColumns[] = {
      &M::frames,        &M::mean_m,         &M::median_m,      &M::plane_std_m,
      &M::hole_rate_pct, &M::valid_pct,      &M::range_m,       &M::azimuth_deg,
      &M::elevation_deg, &M::normal_tilt_deg, &M::panel_width_m, &M::panel_height_m,
      &M::region_px,     &M::subpixel_rms_px, &M::temporal_std_m, &M::sigma_d_px};
  const std::vector<double> widths{3, 0, 5, 1, 3};
  MetricsParams mp;
  mp.threads = 2;
  for (const Cell& c : {MakeCell(4, 0), MakeCell(16, 35, "HD", true), MakeCell(8, 20, "HA", true)}) {
    const SimParams at = With(base, {{"region_spill", {{"width_px", 1}, {"background_rel", 1.5}}}});
    const std::vector<CellMetricsResult> together = SimulateMetricsSpills(at, c, mp, widths);
    ASSERT_EQ(together.size(), widths.size());
    std::set<double> region_sizes;
    for (size_t w = 0; w < widths.size(); ++w) {
      const CellMetricsResult alone = SimulateMetrics(
          With(base, {{"region_spill", {{"width_px", widths[w]}, {"background_rel", 1.5}}}}), c,
          mp);
      const M &a = together[w].metrics, &b = alone.metrics;
      ASSERT_TRUE(b.ok()) << c.name << ": " << b.message;
      EXPECT_EQ(a.status, b.status);
      EXPECT_EQ(a.message, b.message);
      for (double M::*col : kColumns)
        EXPECT_TRUE(a.*col == b.*col || (std::isnan(a.*col) && std::isnan(b.*col)))
            << c.name << " width " << widths[w] << ": " << a.*col << " against " << b.*col;
      EXPECT_EQ(together[w].truth.panel_depth_m, alone.truth.panel_depth_m);
      region_sizes.insert(a.region_px);
    }
    EXPECT_EQ(region_sizes.size(), 4u) << c.name << ": four widths, four regions";
  }
  EXPECT_THROW(SimulateMetricsSpills(base, MakeCell(4, 0), mp, {1, -1}), std::invalid_argument);
}

// The valid share alone (MetricsParams::valid_share_only) is the kernel's, bit for bit: the
// valid share, hole rate, frames and region, on decided and drawn regions, with frames beyond
// the pooled ones and without; every other column missing; a recording without valid depth is
// no panel either way.
TEST(StereoSim, TheValidShareAloneIsTheKernels) {
  using M = records::PanelMetrics;
  constexpr double M::*kShared[] = {&M::valid_pct, &M::hole_rate_pct, &M::frames, &M::region_px};
  constexpr double M::*kLeft[] = {&M::mean_m,          &M::median_m,       &M::plane_std_m,
                                  &M::normal_tilt_deg, &M::panel_width_m, &M::temporal_std_m};
  const SimParams base = Base(0.1, 0.3, 9);
  const SimParams spill =
      With(base, {{"region_spill", {{"width_px", 3}, {"background_rel", 1.5}}}});
  const SimParams holes = With(base, {{"invalidation_gain", {{"gain", 4}}}});
  int checked = 0;
  for (int pooled : {4, 0})
    for (const SimParams& p : {base, spill, holes})
      for (const Cell& c : {MakeCell(4, 0), MakeCell(16, 35, "HD", true), MakeCell(12, 20)}) {
        MetricsParams all;
        all.region.pooled_frames = pooled;
        MetricsParams alone = all;
        alone.valid_share_only = true;
        const M a = SimulateMetrics(p, c, all).metrics, b = SimulateMetrics(p, c, alone).metrics;
        ASSERT_TRUE(a.ok()) << c.name << ": " << a.message;
        EXPECT_EQ(b.status, "ok") << c.name << ": " << b.message;
        for (double M::*col : kShared) EXPECT_EQ(a.*col, b.*col) << c.name;
        for (double M::*col : kLeft) EXPECT_TRUE(std::isnan(b.*col)) << c.name;
        EXPECT_GT(a.valid_pct, 0);
        EXPECT_LT(a.valid_pct, 100);
        ++checked;
      }
  EXPECT_EQ(checked, 18);
  const SimParams blind = Base(0.1, 1.0, 9);
  MetricsParams alone;
  alone.valid_share_only = true;
  const M a = SimulateMetrics(blind, MakeCell(8, 0)).metrics;
  const M b = SimulateMetrics(blind, MakeCell(8, 0), alone).metrics;
  EXPECT_FALSE(a.ok());
  EXPECT_EQ(a.status, b.status);
}

// The k-th smallest by radix selection is std::nth_element's, on values with ties, zeros,
// infinities and subnormals, values apart in their last bits alone (the last, 9-bit pass), and
// (by nth_element itself) on negative values and −0.
TEST(NthSmallest, IsWhatNthElementLeavesAtK) {
  std::mt19937_64 rng(97);
  std::uniform_real_distribution<double> u(0, 1);
  for (size_t n : {1, 7, 256, 257, 1000, 4099, 30000})
    for (int kind = 0; kind < 6; ++kind) {
      std::vector<double> v(n);
      for (double& x : v) {
        std::uint64_t bits;
        const double one = 1.0;
        std::memcpy(&bits, &one, sizeof bits);
        bits += rng() % 300;  // 1 + up to 299 ulps: the top 55 bits shared
        double ulps;
        std::memcpy(&ulps, &bits, sizeof bits);
        x = kind == 0   ? u(rng)
            : kind == 1 ? std::floor(u(rng) * 5) * 0.25  // ties and zeros
            : kind == 2 ? (u(rng) < 0.01 ? INFINITY : u(rng) < 0.01 ? 5e-320 : u(rng) * 1e-3)
            : kind == 3 ? u(rng) - 0.5    // negative values
            : kind == 4 ? (u(rng) < 0.1 ? -0.0 : u(rng))
                        : ulps;
      }
      for (size_t k : {size_t{0}, n / 2, n - 1, n / 3}) {
        std::vector<double> a = v, b = v;
        std::nth_element(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(k), a.end());
        EXPECT_EQ(common::NthSmallest(b, k), a[k]) << "n " << n << " kind " << kind << " k " << k;
      }
    }
}

TEST(StereoSim, ProtocolHasTheArticlesCellsInParallelOrNot) {
  SimParams p = Base(0.1, 0.2, 2);
  const std::vector<Cell> cells = MakeCells(p.protocol);
  ASSERT_EQ(cells.size(), 128u);
  MetricsParams one, two;
  two.threads = 2;
  const auto a = SimulateProtocolMetrics(p, one);
  const auto b = SimulateProtocolMetrics(p, two);
  ASSERT_EQ(a.size(), 128u);
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_TRUE(a[i].metrics.ok()) << a[i].metrics.bag << ": " << a[i].metrics.message;
    EXPECT_EQ(a[i].metrics.median_m, b[i].metrics.median_m);
    EXPECT_EQ(a[i].metrics.bag, cells[i].name + ".bag");
  }
}

}  // namespace
}  // namespace depthbias::sim
