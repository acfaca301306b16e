// The parts of the gap diagnosis against known truth: interpolation, the table's checks and
// folds, the noise from replicates, the shares of the gap by factor, the χ² tail, the JSON text,
// the region_spill effect's signature in the simulator, and a table's simulations kept as bytes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <stdexcept>

#include "gap/candidates.h"
#include "gap/design.h"
#include "gap/fit.h"
#include "gap/json.h"
#include "gap/limits.h"
#include "gap/localize.h"
#include "gap/noise.h"
#include "gap/placement.h"
#include "gap/robust_covariance.h"
#include "gap/select.h"
#include "gap/sim_cache.h"
#include "gap/simulations.h"
#include "gap/smooth.h"
#include "gap/unexplained.h"
#include "sim/config_yaml.h"
#include "sim/sim_metrics.h"
#include "sim/stereo_sim.h"
#include "support/article.h"

namespace depthbias::gap {
namespace {

records::PanelMetrics Row(double d, double a, const std::string& preset, const std::string& emitter,
                          const std::string& light = "daylight") {
  records::PanelMetrics r;
  r.bag = light + "_" + preset + "_" + emitter + "_" + std::to_string(d) + "_" + std::to_string(a);
  r.light = light;
  r.preset = preset;
  r.emitter = emitter;
  r.distance_m = d;
  r.angle_deg = a;
  r.median_m = d;
  r.mean_m = d + 0.01;
  r.plane_std_m = 0.05;
  r.valid_pct = 50;
  r.hole_rate_pct = 50;
  return r;
}

// A sensor that lists no scenario (every cell takes the fallback's σ_d and hole probability), at
// a seed.
sim::SimParams FallbackSensor(std::uint64_t seed, double invalid_prob = 0.2,
                              double sigma_d_px = 0.08) {
  sim::SimParams p;
  p.sensor.fallback = {"", "", sigma_d_px, invalid_prob};
  p.seed = seed;
  return p;
}

// Each distance's emitter-off and emitter-on rows, at one angle and preset, in daylight.
std::vector<records::PanelMetrics> Twins(std::initializer_list<double> distances, double angle,
                                         const std::string& preset) {
  std::vector<records::PanelMetrics> rows;
  for (double dist : distances)
    for (const char* emitter : {"off", "on"}) rows.push_back(Row(dist, angle, preset, emitter));
  return rows;
}

std::vector<records::PanelMetrics> Table() {
  std::vector<records::PanelMetrics> rows;
  for (const char* light : {"daylight", "sunset"})
    for (const char* emitter : {"off", "on"})
      for (double a : {0.0, 20.0})
        for (const char* preset : {"HA", "HD"})
          for (double d : {4.0, 8.0, 12.0}) rows.push_back(Row(d, a, preset, emitter, light));
  return rows;
}

TEST(Pchip, PassesThroughNodesAndKeepsMonotoneDataMonotone) {
  const double x[] = {0, 1, 2, 4, 8};
  const double y[] = {0, 0.1, 3, 3.2, 10};
  for (int i = 0; i < 5; ++i) EXPECT_DOUBLE_EQ(Pchip(x, y, 5, x[i]), y[i]);
  double last = -1;
  for (double t = 0; t <= 8; t += 0.01) {
    const double v = Pchip(x, y, 5, t);
    EXPECT_GE(v, last - 1e-12) << t;  // no overshoot: monotone data stay monotone
    last = v;
  }
  EXPECT_DOUBLE_EQ(Pchip(x, y, 5, -3), 0);  // clamped
  EXPECT_DOUBLE_EQ(Pchip(x, y, 5, 30), 10);
  const double lx[] = {0, 1, 2}, ly[] = {1, 3, 5};  // a line stays a line
  EXPECT_NEAR(Pchip(lx, ly, 3, 1.37), 3.74, 1e-12);
}

TEST(Design, CellsScenariosPairsAndFolds) {
  Design d;
  std::string why;
  auto rows = Table();
  rows[5].status = "no_panel";
  ASSERT_TRUE(BuildDesign(rows, &d, &why)) << why;
  EXPECT_EQ(d.num_cells(), 47);
  ASSERT_EQ(d.skipped.size(), 1u);
  EXPECT_NE(d.skipped[0].find("no_panel"), std::string::npos);
  EXPECT_EQ(d.num_scenarios(), 4);
  EXPECT_EQ(d.num_metrics(), 4);  // the extra metrics are empty in every row
  EXPECT_EQ(d.pairs.size(), 23u);  // 24 test points, one lost its emitter-off row
  for (const auto& p : d.pairs) {
    EXPECT_TRUE(d.cells[p[0]].emitter_on);
    EXPECT_FALSE(d.cells[p[1]].emitter_on);
    EXPECT_EQ(d.cells[p[0]].distance_m, d.cells[p[1]].distance_m);
  }
  std::vector<int> fold;
  int folds = 0;
  ASSERT_TRUE(Folds(d, Holdout{}, &fold, &folds, &why)) << why;
  EXPECT_EQ(folds, 3);
  for (int c = 0; c < d.num_cells(); ++c)
    EXPECT_EQ(fold[c], static_cast<int>(d.cells[c].distance_m / 4) - 1);
  Holdout h;
  ASSERT_TRUE(ParseHoldout("light=sunset", &h, &why));
  ASSERT_TRUE(Folds(d, h, &fold, &folds, &why));
  EXPECT_EQ(folds, 1);
  for (int c = 0; c < d.num_cells(); ++c) EXPECT_EQ(fold[c] == 0, d.cells[c].light == "sunset");
  ASSERT_TRUE(ParseHoldout("point", &h, &why));
  ASSERT_TRUE(Folds(d, h, &fold, &folds, &why));
  EXPECT_EQ(folds, 6);
  EXPECT_FALSE(ParseHoldout("angle", &h, &why));
  ASSERT_TRUE(ParseHoldout("preset=XY", &h, &why));
  EXPECT_FALSE(Folds(d, h, &fold, &folds, &why));
  EXPECT_NE(why.find("no row"), std::string::npos) << why;
}

TEST(Design, RefusesBadRowsWithTheRowNamed) {
  Design d;
  std::string why;
  auto rows = Table();
  rows[3].plane_std_m = NAN;
  EXPECT_FALSE(BuildDesign(rows, &d, &why));
  EXPECT_NE(why.find("row 4 (" + rows[3].bag + "): plane_std_m"), std::string::npos) << why;
  rows = Table();
  rows[0].emitter = "maybe";
  EXPECT_FALSE(BuildDesign(rows, &d, &why));
  EXPECT_NE(why.find("emitter"), std::string::npos) << why;
  EXPECT_FALSE(BuildDesign({}, &d, &why));
  EXPECT_NE(why.find("no rows"), std::string::npos) << why;
}

TEST(Noise, ReplicatesGiveTheNoiseOfOneResidualAndTheEmitterMismatchApart) {
  Design d;
  std::string why;
  auto rows = Table();
  // The camera's emitter adds 0.05 m at 10 m to the median (the simulator's nothing), and the
  // twins differ by ±0.04 m at 10 m about that (signs alternating with the angle), both shaped
  // as (Z / 10 m)². Each scenario and distance holds two twins: their mean (the mismatch) is
  // removed, the deviations ±0.04 inflated by √(2/1), so the robust scale is
  // 1.4826·0.04·√2/√2 = 1.4826·0.04.
  for (auto& r : rows) {
    const double shape = std::pow(r.distance_m / 10.0, 2);
    const double twin = (r.angle_deg == 0 ? 0.02 : -0.02) * (r.emitter == "on" ? 1 : -1);
    r.median_m = r.distance_m + (twin + (r.emitter == "on" ? 0.05 : 0.0)) * shape;
  }
  ASSERT_TRUE(BuildDesign(rows, &d, &why)) << why;
  Simulations s;
  s.metrics = d.metrics;
  s.base.assign(d.real.size(), 0.0);
  for (int c = 0; c < d.num_cells(); ++c) {
    s.depth_m.push_back(d.cells[c].distance_m);
    for (int k = 0; k < d.num_metrics(); ++k) {
      const double v = d.real[c * d.num_metrics() + k];
      s.base[c * d.num_metrics() + k] = k == 0 ? 0.0 : v;  // sim: no bias, the rest equal
    }
  }
  const NoiseEstimate n = EstimateNoise(d, s);
  EXPECT_NEAR(n.scale[0], 1.4826 * 0.04, 1e-9);
  EXPECT_EQ(n.method[0], "replicates");
  EXPECT_EQ(n.pairs[0], 24);
  int groups = 0;
  for (const EmitterGap& e : n.emitter) {
    if (e.k != 0) continue;
    ++groups;
    EXPECT_EQ(e.pairs, 2);
    EXPECT_NEAR(e.mean, 0.05 * std::pow(e.distance_m / 10.0, 2), 1e-9);
    EXPECT_GT(e.z, 0);
  }
  EXPECT_EQ(groups, 12);  // 4 scenarios × 3 distances
  EXPECT_EQ(n.method[2], "replicates + floor");  // identical rows: the floor
  // The quantization of the median adds in quadrature: one subpixel step at 12 m.
  const double q = 144.0 * s.sensor.subpixel_step_px / (s.sensor.focal_px() * s.sensor.baseline_m);
  int far = 0;
  while (d.cells[far].distance_m != 12) ++far;
  EXPECT_NEAR(n.Of(d, s, far, 0),
              std::hypot(n.scale[0] * 1.44, q / std::sqrt(12.0)), 1e-12);
}

// The simulation's own scatter: the shifted base departs from the base by ±0.03 at 10 m in the
// median bias (shaped as (Z / 10 m)²), alternating over the cells: its root mean square over √2
// is one simulated value's scatter, and it adds in quadrature to the replicate noise. Only the
// cells marked in `train` count: marking the cells whose shift is 0.09 instead gives 0.09/√2.
TEST(Noise, TheSimulationsOwnScatterAddsInQuadrature) {
  Design d;
  std::string why;
  ASSERT_TRUE(BuildDesign(Table(), &d, &why)) << why;
  Simulations s;
  s.metrics = d.metrics;
  s.base = d.real;
  s.shifted = d.real;
  const int kk = d.num_metrics();
  std::vector<char> train(d.num_cells(), 0);
  for (int c = 0; c < d.num_cells(); ++c) {
    s.depth_m.push_back(d.cells[c].distance_m);
    const double shape = std::pow(d.cells[c].distance_m / 10.0, 2);
    const bool odd = c % 2 == 1;
    s.shifted[c * kk] += (odd ? 0.09 : (c % 4 == 0 ? 0.03 : -0.03)) * shape;
    train[c] = odd;
  }
  std::vector<char> even(d.num_cells());
  for (int c = 0; c < d.num_cells(); ++c) even[c] = !train[c];
  const NoiseEstimate n = EstimateNoise(d, s, even);
  ASSERT_EQ(n.simulation.size(), static_cast<size_t>(kk));
  EXPECT_NEAR(n.simulation[0], 0.03 / std::sqrt(2.0), 1e-12);
  EXPECT_EQ(n.simulation[1], 0.0);  // the other metrics: no shift
  EXPECT_NEAR(EstimateNoise(d, s, train).simulation[0], 0.09 / std::sqrt(2.0), 1e-12);
  int far = 0;
  while (d.cells[far].distance_m != 12) ++far;
  NoiseEstimate without = n;
  without.simulation.clear();
  EXPECT_NEAR(n.Of(d, s, far, 0),
              std::hypot(without.Of(d, s, far, 0), 0.03 / std::sqrt(2.0) * 1.44), 1e-12);
}

// The shifted base moves each panel sideways by less than a pixel: the median, which no window
// decides, stays within two steps of its quantization at 35° off axis (ten pixels move it
// 17 mm at 4 m, past the 11 mm of two steps); with shift_px 0 there is no such run.
TEST(Simulations, TheShiftedBaseMovesPanelsByLessThanAPixel) {
  const sim::SimParams p = FallbackSensor(11);
  const std::vector<records::PanelMetrics> rows = Twins({4, 16}, 35, "HA");
  Design d;
  std::string why;
  ASSERT_TRUE(BuildDesign(rows, &d, &why)) << why;
  SimulateOptions options;
  options.frames = 4;
  const Simulations s = SimulateDesign(p, d, {}, options);
  ASSERT_EQ(s.shifted.size(), s.base.size());
  EXPECT_EQ(s.runs, 7);  // base, two Jacobians (± each), shifted, moved further
  const int kk = d.num_metrics();
  bool any_moved = false;
  for (int c = 0; c < d.num_cells(); ++c) {
    const double z = s.depth_m[c];
    const double step = z * z * p.sensor.subpixel_step_px / (p.sensor.focal_px() * p.sensor.baseline_m);
    EXPECT_LE(std::fabs(s.shifted[c * kk] - s.base[c * kk]), 2 * step + 1e-9) << d.cells[c].name;
    for (int k = 0; k < kk; ++k) any_moved = any_moved || s.shifted[c * kk + k] != s.base[c * kk + k];
  }
  EXPECT_TRUE(any_moved);
  options.shift_px = 0;
  const Simulations none = SimulateDesign(p, d, {}, options);
  EXPECT_TRUE(none.shifted.empty());
  EXPECT_EQ(none.runs, 6);
  options.shift_px = -1;
  EXPECT_THROW(SimulateDesign(p, d, {}, options), std::invalid_argument);
  options.shift_px = 0;
  options.placement_probe = -0.02;
  EXPECT_THROW(SimulateDesign(p, d, {}, options), std::invalid_argument);
}

// One candidate's surface over rows (seed p's, `frames` frames a cell), each node's table in the
// metrics no smoothing touches (smooth.h) checked against the whole table simulated at that node
// alone, bit for bit. Returns the (node values, cell) pairs that the node moves from the base.
std::vector<std::pair<std::vector<double>, sim::Cell>> EveryNodeIsTheTableAlone(
    const sim::SimParams& p, const std::vector<records::PanelMetrics>& rows,
    const std::string& effect, int frames) {
  std::vector<std::pair<std::vector<double>, sim::Cell>> moved;
  Design d;
  std::string why;
  EXPECT_TRUE(BuildDesign(rows, &d, &why)) << why;
  std::vector<Candidate> cand;
  EXPECT_TRUE(SelectCandidates(effect, &cand, &why)) << why;
  if (cand.size() != 1) return moved;
  SimulateOptions options;
  options.frames = frames;
  const Simulations s = SimulateDesign(p, d, cand, options);
  EXPECT_EQ(s.surfaces.size(), 1u);
  const Surface& surf = s.surfaces[0];
  const std::vector<Axis>& axes = cand[0].axes;
  const int kk = d.num_metrics(), last = static_cast<int>(axes.back().nodes.size());
  int compared = 0;
  for (int node = 0; node < surf.num_nodes; ++node) {
    std::vector<double> values{axes[0].nodes[axes.size() == 1 ? node : node / last]};
    if (axes.size() == 2) values.push_back(axes[1].nodes[node % last]);
    if (IsNeutral(cand[0], values)) continue;
    sim::SimParams q = p;
    EXPECT_TRUE(sim::BuildDepartures({SpecAt(cand[0], values)}, &q.departures, &why)) << why;
    const std::vector<double> whole = SimulateValues({q}, d, options);
    for (int c = 0; c < d.num_cells(); ++c)
      for (int k = 0; k < kk; ++k) {
        if (InfoOf(d.metrics[k]).window) continue;
        const size_t o = static_cast<size_t>(c) * kk + k;
        const double v = surf.table[o * surf.num_nodes + node];
        if (std::isnan(whole[o])) continue;  // a gap of the grid, filled from a neighbour
        EXPECT_EQ(v, whole[o]) << d.cells[c].name << " " << InfoOf(d.metrics[k]).name << " "
                               << effect << " node " << node;
        ++compared;
        if (v != s.base[o]) moved.push_back({values, d.cells[c]});
      }
  }
  EXPECT_GT(compared, 0);
  return moved;
}

// With lateral phases (lateral_phase_px), the valid share of an effect that moves the window is
// the base's plus its departure with every panel moved alike (LateralPhases: one draw a test
// point, its recordings sharing it, within the bound); every other metric and every effect that
// does not move the window are as without, one more simulation a node and one for the base.
TEST(Simulations, TheValidShareOfAWindowMoverIsReadAtLateralPhases) {
  const sim::SimParams p = FallbackSensor(43);
  std::vector<records::PanelMetrics> rows = Twins({8, 16}, 0, "HA");
  for (const auto& r : Twins({16}, 0, "HD")) rows.push_back(r);
  for (const auto& r : Twins({12}, 35, "HA")) rows.push_back(r);
  Design d;
  std::string why;
  ASSERT_TRUE(BuildDesign(rows, &d, &why)) << why;
  std::vector<Candidate> cand;
  ASSERT_TRUE(SelectCandidates("disparity_offset,panel_tilt", &cand, &why)) << why;
  ASSERT_TRUE(cand[0].moves_window && !cand[1].moves_window);
  SimulateOptions nominal;
  nominal.frames = 4;
  nominal.lateral_phase_px = 0;
  SimulateOptions lateral = nominal;
  lateral.lateral_phase_px = 0.5;
  const Simulations a = SimulateDesign(p, d, cand, nominal);
  const Simulations b = SimulateDesign(p, d, cand, lateral);
  int movers = 0;
  for (double v : cand[0].axes[0].nodes) movers += !IsNeutral(cand[0], {v});
  EXPECT_EQ(b.runs, a.runs + 1 + movers);
  EXPECT_EQ(a.base, b.base);
  EXPECT_EQ(a.surfaces[1].table, b.surfaces[1].table);
  const Design moved = LateralPhases(d, p, 0.5);
  const double px_deg = 180 / M_PI / p.sensor.focal_px();
  std::map<std::string, double> shift;  // per test point: light, distance, angle
  for (int c = 0; c < d.num_cells(); ++c) {
    const double by = moved.cells[c].angle_deg - d.cells[c].angle_deg;
    EXPECT_LE(std::fabs(by), 0.5 * px_deg + 1e-12);
    EXPECT_EQ(moved.cells[c].name, d.cells[c].name);
    const std::string point = d.cells[c].light + "|" + std::to_string(d.cells[c].distance_m) +
                              "|" + std::to_string(d.cells[c].angle_deg);
    const auto [it, first] = shift.emplace(point, by);
    if (!first) {
      EXPECT_EQ(it->second, by) << d.cells[c].name << ": one draw a test point";
    }
  }
  ASSERT_EQ(shift.size(), 3u);
  EXPECT_NE(shift.begin()->second, std::next(shift.begin())->second);
  const std::vector<double> base_moved = SimulateValues({p}, moved, nominal);
  const int kk = d.num_metrics();
  const int valid_k = static_cast<int>(
      std::find(d.metrics.begin(), d.metrics.end(), kValidPct) - d.metrics.begin());
  ASSERT_LT(valid_k, kk);
  const Surface &sa = a.surfaces[0], &sb = b.surfaces[0];
  int differ = 0;
  for (int node = 0; node < sb.num_nodes; ++node) {
    const std::vector<double> values{cand[0].axes[0].nodes[node]};
    if (IsNeutral(cand[0], values)) continue;
    sim::SimParams q = p;
    ASSERT_TRUE(sim::BuildDepartures({SpecAt(cand[0], values)}, &q.departures, &why)) << why;
    const std::vector<double> at = SimulateValues({q}, moved, nominal);
    for (int c = 0; c < d.num_cells(); ++c)
      for (int k = 0; k < kk; ++k) {
        const size_t o = static_cast<size_t>(c) * kk + k;
        const double va = sa.table[o * sa.num_nodes + node], vb = sb.table[o * sb.num_nodes + node];
        if (k != valid_k) {
          EXPECT_EQ(va, vb) << d.cells[c].name << " node " << node;
          continue;
        }
        if (std::isnan(at[o])) continue;  // a gap of the grid, filled from a neighbour
        EXPECT_NEAR(vb, b.base[o] + (at[o] - base_moved[o]), 1e-9)
            << d.cells[c].name << " node " << node;
        differ += std::fabs(vb - va) > 1e-6;
      }
  }
  EXPECT_GT(differ, 0) << "other phases, other steps";
  lateral.lateral_phase_px = -1;
  EXPECT_THROW(SimulateDesign(p, d, cand, lateral), std::invalid_argument);
}

// A selection is checked against the table (the nested folds' held-out cells, the verification)
// as the mean of its cells as placed and at their lateral phases, the phases the surfaces read
// the valid share at: without phases it is the plain simulation, bit for bit.
TEST(Simulations, ASelectionIsSimulatedAtTwoPhases) {
  sim::SimParams p = FallbackSensor(47);
  std::string why;
  ASSERT_TRUE(sim::BuildDepartures({{"disparity_offset", {{"delta_px", 0.3}}}}, &p.departures,
                                   &why))
      << why;
  std::vector<records::PanelMetrics> rows = Twins({8, 16}, 35, "HD");
  for (const auto& r : Twins({12}, 0, "HA")) rows.push_back(r);
  Design d;
  ASSERT_TRUE(BuildDesign(rows, &d, &why)) << why;
  SimulateOptions options;
  options.frames = 4;
  options.lateral_phase_px = 0;
  EXPECT_EQ(SimulateSelection({p}, d, p, options), SimulateValues({p}, d, options));
  options.lateral_phase_px = 0.5;
  const std::vector<double> nominal = SimulateValues({p}, d, options);
  const std::vector<double> moved = SimulateValues({p}, LateralPhases(d, p, 0.5), options);
  const std::vector<double> both = SimulateSelection({p}, d, p, options);
  ASSERT_EQ(both.size(), nominal.size());
  int differ = 0;
  for (size_t o = 0; o < both.size(); ++o) {
    if (!std::isfinite(nominal[o]) || !std::isfinite(moved[o])) {
      EXPECT_TRUE(both[o] == nominal[o] || (std::isnan(both[o]) && std::isnan(nominal[o])));
      continue;
    }
    EXPECT_DOUBLE_EQ(both[o], 0.5 * (nominal[o] + moved[o])) << "observation " << o;
    differ += both[o] != nominal[o];
  }
  EXPECT_GT(differ, 0) << "the second phase is simulated";
}

// The emitter's gain alone changes nothing with the emitter off: its nodes simulate the
// emitter-on cells alone and take the base's for the others. Every node's table is then what
// the whole table simulated at that gain gives (a recording listed twice included); and every
// other registered effect, alone or beside the gain, does not take the shortcut (its departures
// are not the emitter's alone).
TEST(Simulations, AnEmitterGainNodeIsTheWholeTableSimulatedAtThatGain) {
  const sim::SimParams p = FallbackSensor(23);
  std::vector<records::PanelMetrics> rows = Twins({4, 12}, 10, "HD");
  rows.insert(rows.begin() + 1, Row(12, 10, "HD", "on"));  // listed twice, out of order
  const auto moved = EveryNodeIsTheTableAlone(p, rows, "emitter_gain", 4);
  EXPECT_FALSE(moved.empty()) << "the gain moves the emitter-on cells";
  for (const auto& [values, cell] : moved)
    EXPECT_TRUE(cell.emitter_on) << cell.name << " moved by gain " << values[0];
  std::string why;
  sim::Departures both;
  ASSERT_TRUE(sim::BuildDepartures({{"emitter_gain", {{"gain", 2.0}}}}, &both, &why)) << why;
  EXPECT_TRUE(both.OnlyEmitter());
  ASSERT_TRUE(sim::BuildDepartures({{"emitter_gain", {{"gain", 2.0}}}, {"panel_tilt", {}}},
                                   &both, &why))
      << why;
  EXPECT_FALSE(both.OnlyEmitter());
  for (const sim::EffectInfo& e : sim::EffectRegistry()) {
    if (e.name == "emitter_gain") continue;
    sim::Departures other;
    ASSERT_TRUE(sim::BuildDepartures({{e.name, {}}}, &other, &why)) << why;
    EXPECT_FALSE(other.OnlyEmitter()) << e.name << " at its defaults";
  }
}

// region_spill's widths at one background are simulated together (sim::SimulateMetricsSpills:
// one sensor, footprint and plane a cell for all of them). Every node's table is what the whole
// table simulated at that width and background alone gives (a recording listed twice included);
// two sets of departures are grouped only when they differ by the width alone.
TEST(Simulations, ARegionSpillNodeIsTheWholeTableSimulatedAtThatWidth) {
  const sim::SimParams p = FallbackSensor(29, 0.2, 0.1);
  const std::vector<records::PanelMetrics> rows{Row(16, 20, "HD", "on"), Row(4, 0, "HA", "off"),
                                                Row(16, 20, "HD", "on"), Row(8, 35, "HA", "on")};
  std::set<double> widths_apart;  // the widths that move a metric from the base's
  for (const auto& [values, cell] : EveryNodeIsTheTableAlone(p, rows, "region_spill", 3))
    widths_apart.insert(values[0]);
  EXPECT_EQ(widths_apart.size(), 5u) << "each width draws a region of its own";
  std::string why;
  sim::Departures a, b;
  ASSERT_TRUE(sim::BuildDepartures({{"region_spill", {{"width_px", 1}, {"background_rel", 2}}}},
                                   &a, &why))
      << why;
  ASSERT_TRUE(sim::BuildDepartures({{"region_spill", {{"width_px", 4}, {"background_rel", 2}}}},
                                   &b, &why))
      << why;
  EXPECT_TRUE(a.SameButSpill(b));
  ASSERT_TRUE(sim::BuildDepartures({{"region_spill", {{"width_px", 4}, {"background_rel", 3}}}},
                                   &b, &why))
      << why;
  EXPECT_FALSE(a.SameButSpill(b)) << "another background";
  // Every other effect beside the spill, and each of its parameters moved alone: never the same.
  for (const sim::EffectInfo& e : sim::EffectRegistry()) {
    if (e.name == "region_spill") continue;
    const sim::EffectSpec spill{"region_spill", {{"width_px", 4}, {"background_rel", 2}}};
    sim::Departures at_defaults;
    ASSERT_TRUE(sim::BuildDepartures({spill, {e.name, {}}}, &at_defaults, &why)) << why;
    EXPECT_FALSE(a.SameButSpill(at_defaults)) << e.name << " at its defaults beside the spill";
    for (const sim::EffectParamInfo& param : e.params) {
      const double moved =
          param.default_value != param.max_value ? param.max_value : param.min_value;
      ASSERT_TRUE(sim::BuildDepartures({spill, {e.name, {{param.name, moved}}}}, &b, &why))
          << why;
      EXPECT_FALSE(at_defaults.SameButSpill(b)) << e.name << "'s " << param.name << " moved";
    }
  }
}

// Two vectors of the same values, bit for bit (NaN included).
bool SameBits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

// A table's simulations as bytes and back (sim_cache.h): every value the same, bit for bit, and
// the parts SimulateDesign makes from the design, sensor and candidates made again.
TEST(SimulationsKept, DecodedSimulationsAreTheSimulationsBitForBit) {
  const sim::SimParams p = FallbackSensor(31);
  const std::vector<records::PanelMetrics> rows = Twins({4, 16}, 35, "HA");
  Design d;
  std::string why;
  ASSERT_TRUE(BuildDesign(rows, &d, &why)) << why;
  std::vector<Candidate> cand;
  ASSERT_TRUE(SelectCandidates("disparity_offset,region_spill", &cand, &why)) << why;
  SimulateOptions options;
  options.frames = 2;
  options.replica = true;
  const Simulations s = SimulateDesign(p, d, cand, options);
  const std::string key = SimulationsKey("protocol x", p, d, cand, options);
  ASSERT_FALSE(key.empty());
  const std::string bytes = EncodeSimulations(s, key);
  Simulations back;
  ASSERT_TRUE(DecodeSimulations(bytes, key, p, d, cand, &back, &why)) << why;
  for (auto m : {&Simulations::base, &Simulations::depth_m, &Simulations::jac_log_sigma,
                 &Simulations::jac_logit_p, &Simulations::replica, &Simulations::shifted,
                 &Simulations::moved})
    EXPECT_TRUE(SameBits(s.*m, back.*m));
  EXPECT_FALSE(back.replica.empty());
  EXPECT_EQ(back.moved_rel, s.moved_rel);
  EXPECT_EQ(back.runs, s.runs);
  EXPECT_EQ(back.cell_names, s.cell_names);
  EXPECT_EQ(back.metrics, s.metrics);
  EXPECT_EQ(FormatSensorYaml(back.sensor, {}), FormatSensorYaml(s.sensor, {}));
  ASSERT_EQ(back.surfaces.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(back.surfaces[i].candidate.effect, cand[i].effect);
    EXPECT_EQ(back.surfaces[i].num_nodes, s.surfaces[i].num_nodes);
    EXPECT_TRUE(SameBits(back.surfaces[i].table, s.surfaces[i].table));
  }
  EXPECT_TRUE(back.Matches(d));

  // Refused, each with its reason: another key, a byte altered, the end cut, another format,
  // other candidates.
  auto refused = [&](const std::string& b, const std::string& k,
                     const std::vector<Candidate>& c) {
    Simulations out;
    std::string reason;
    EXPECT_FALSE(DecodeSimulations(b, k, p, d, c, &out, &reason));
    return reason;
  };
  EXPECT_NE(refused(bytes, key + " ", cand).find("other cells"), std::string::npos);
  std::string altered = bytes;
  altered[altered.size() / 2] ^= 4;
  EXPECT_NE(refused(altered, key, cand).find("checksum"), std::string::npos);
  EXPECT_NE(refused(bytes.substr(0, bytes.size() - 9), key, cand).find("checksum"),
            std::string::npos);
  EXPECT_NE(refused("", key, cand).find("not a depthbias"), std::string::npos);
  EXPECT_NE(refused("depthbias gap simulations 0\n" + bytes, key, cand).find("not a depthbias"),
            std::string::npos);
  EXPECT_NE(refused(bytes, key, {cand[0]}).find("surfaces for"), std::string::npos);
  // Whole and checked, but of other sizes than the design's and the candidates' grids.
  Simulations shorter = s;
  shorter.moved.pop_back();
  EXPECT_NE(refused(EncodeSimulations(shorter, key), key, cand).find("moved holds"),
            std::string::npos);
  Simulations fewer = s;
  fewer.surfaces[1].table.resize(fewer.surfaces[1].table.size() - 1);
  EXPECT_NE(refused(EncodeSimulations(fewer, key), key, cand).find("does not fit"),
            std::string::npos);
  Simulations no_replica = s;
  no_replica.replica.clear();  // a part that may be absent
  Simulations decoded;
  EXPECT_TRUE(DecodeSimulations(EncodeSimulations(no_replica, key), key, p, d, cand, &decoded,
                                &why))
      << why;
  EXPECT_TRUE(decoded.replica.empty());
}

// The key names what the simulations are made of, and nothing else: the threads change no
// result and no key; the origin, seed, frames, a cell, a candidate's grid and the sensor each
// make another key; no origin, or a base with departures of its own, none.
TEST(SimulationsKept, TheKeyNamesWhatTheSimulationsAreMadeOf) {
  const sim::SimParams p = FallbackSensor(31);
  Design d;
  std::string why;
  ASSERT_TRUE(BuildDesign(Twins({4, 16}, 35, "HA"), &d, &why)) << why;
  std::vector<Candidate> cand;
  ASSERT_TRUE(SelectCandidates("disparity_offset", &cand, &why)) << why;
  const SimulateOptions options;
  const std::string key = SimulationsKey("protocol x", p, d, cand, options);
  ASSERT_FALSE(key.empty());
  SimulateOptions threads = options;
  threads.threads = options.threads + 3;
  EXPECT_EQ(SimulationsKey("protocol x", p, d, cand, threads), key);
  std::set<std::string> keys{key};
  keys.insert(SimulationsKey("protocol y", p, d, cand, options));
  sim::SimParams seed = p;
  seed.seed = p.seed + 1;
  keys.insert(SimulationsKey("protocol x", seed, d, cand, options));
  SimulateOptions frames = options;
  frames.frames = options.frames + 1;
  keys.insert(SimulationsKey("protocol x", p, d, cand, frames));
  Design moved = d;
  moved.cells[1].distance_m += 1e-9;
  keys.insert(SimulationsKey("protocol x", p, moved, cand, options));
  std::vector<Candidate> other = cand;
  other[0].axes[0].nodes.back() += 1e-9;
  keys.insert(SimulationsKey("protocol x", p, d, other, options));
  sim::SimParams sensor = p;
  sensor.sensor.fallback.sigma_d_px *= 1.01;
  keys.insert(SimulationsKey("protocol x", sensor, d, cand, options));
  EXPECT_EQ(keys.size(), 7u);
  // Every other option, a cell's every field, the metrics and an axis's every field.
  const std::vector<std::function<void(SimulateOptions&)>> option_changes{
      [](SimulateOptions& o) { o.region_margin_px += 0.25; },
      [](SimulateOptions& o) { o.step_log_sigma *= 2; },
      [](SimulateOptions& o) { o.step_logit_p *= 2; },
      [](SimulateOptions& o) { o.replica = !o.replica; },
      [](SimulateOptions& o) { o.shift_px += 0.5; },
      [](SimulateOptions& o) { o.dither_quantization = !o.dither_quantization; },
      [](SimulateOptions& o) { o.placement_probe *= 2; }};
  for (const auto& change : option_changes) {
    SimulateOptions o = options;
    change(o);
    keys.insert(SimulationsKey("protocol x", p, d, cand, o));
  }
  const std::vector<std::function<void(Design&)>> design_changes{
      [](Design& x) { x.cells[0].angle_deg += 1; },
      [](Design& x) { x.cells[0].preset = "HD"; },
      [](Design& x) { x.cells[0].emitter_on = !x.cells[0].emitter_on; },
      [](Design& x) { x.cells[0].light = "sunset"; },
      [](Design& x) { x.cells[0].name += "_"; },
      [](Design& x) { x.cells[0].panel = !x.cells[0].panel; },
      [](Design& x) { x.metrics.pop_back(); }};
  for (const auto& change : design_changes) {
    Design x = d;
    change(x);
    keys.insert(SimulationsKey("protocol x", p, x, cand, options));
  }
  const std::vector<std::function<void(Candidate&)>> candidate_changes{
      [](Candidate& c) { c.range_law = !c.range_law; },
      [](Candidate& c) { c.moves_window = !c.moves_window; },
      [](Candidate& c) { c.effect = "depth_scale"; },
      [](Candidate& c) { c.axes[0].param = "x"; },
      [](Candidate& c) { c.axes[0].neutral += 1; },
      [](Candidate& c) { c.axes[0].discrete = !c.axes[0].discrete; },
      [](Candidate& c) { c.axes[0].log_scale = !c.axes[0].log_scale; },
      [](Candidate& c) { c.axes[0].reference += 1; },
      [](Candidate& c) { c.axes[0].min_value = -5; },
      [](Candidate& c) { c.axes[0].max_value = 5; }};
  for (const auto& change : candidate_changes) {
    std::vector<Candidate> x = cand;
    change(x[0]);
    keys.insert(SimulationsKey("protocol x", p, d, x, options));
  }
  EXPECT_EQ(keys.size(), 7u + option_changes.size() + design_changes.size() +
                             candidate_changes.size());
  EXPECT_EQ(SimulationsKey("", p, d, cand, options), "");
  sim::SimParams departed = p;
  ASSERT_TRUE(sim::BuildDepartures({{"disparity_offset", {{"delta_px", 0.1}}}},
                                   &departed.departures, &why))
      << why;
  EXPECT_EQ(SimulationsKey("protocol x", departed, d, cand, options), "");
}

// The sandwich over units (robust_covariance.h), worked out by hand on a mean: J a column of
// ones over n rows, H⁻¹ = 1/n, so the variance is G/(G − 1) · Σ_u (Σ_{i∈u} r_i)² / n². Rows of
// one unit that move together count once: three units of two rows each, every pair equal,
// give twice the variance of the same six residuals in six units (2.5 times with the factors
// 3/2 and 6/5). A prior row beyond the data is left out; one unit gives NaN.
TEST(RobustCovariance, CountsRowsThatMoveTogetherOnce) {
  const std::vector<double> r{0.5, 0.5, -1.0, -1.0, 0.25, 0.25, 10.0};  // the last a prior's
  const Eigen::MatrixXd inv = Eigen::MatrixXd::Constant(1, 1, 1.0 / 6);
  const Eigen::MatrixXd j = Eigen::MatrixXd::Ones(7, 1);
  const Eigen::MatrixXd paired = ClusterRobustCovariance(inv, j, r, {0, 0, 1, 1, 2, 2});
  const double sums = 1.0 + 4.0 + 0.25;  // (0.5 + 0.5)², (−2)², (0.5)²
  EXPECT_NEAR(paired(0, 0), 3.0 / 2.0 * sums / 36.0, 1e-15);
  const Eigen::MatrixXd alone = ClusterRobustCovariance(inv, j, r, {0, 1, 2, 3, 4, 5});
  const double squares = 2 * (0.25 + 1.0 + 0.0625);
  EXPECT_NEAR(alone(0, 0), 6.0 / 5.0 * squares / 36.0, 1e-15);
  EXPECT_NEAR(paired(0, 0), 2.5 * alone(0, 0), 1e-15);
  EXPECT_TRUE(std::isnan(ClusterRobustCovariance(inv, j, r, {4, 4, 4, 4, 4, 4})(0, 0)));
}

// A simulation that reads every metric but the median bias as the real one (and the median bias
// as 0): the median bias is the only gap.
Simulations MedianBiasOnly(const Design& d) {
  Simulations s;
  s.metrics = d.metrics;
  s.base.assign(d.real.size(), 0.0);
  for (int c = 0; c < d.num_cells(); ++c) {
    s.depth_m.push_back(d.cells[c].distance_m);
    for (int k = 1; k < d.num_metrics(); ++k)
      s.base[c * d.num_metrics() + k] = d.real[c * d.num_metrics() + k];
  }
  return s;
}

// The article's grid: 2 lights × 4 angles × 4 distances × 2 presets × emitter off/on.
std::vector<records::PanelMetrics> ArticleGrid() {
  std::vector<records::PanelMetrics> rows;
  for (const char* light : {"daylight", "sunset"})
    for (double a : {0.0, 10.0, 20.0, 35.0})
      for (double dist : {4.0, 8.0, 12.0, 16.0})
        for (const char* preset : {"HA", "HD"})
          for (const char* emitter : {"off", "on"})
            rows.push_back(Row(dist, a, preset, emitter, light));
  return rows;
}

// The placement estimate of a table against MedianBiasOnly.
PlacementEstimate PlacementOf(const std::vector<records::PanelMetrics>& rows) {
  Design d;
  std::string why;
  if (!BuildDesign(rows, &d, &why)) throw std::runtime_error(why);
  const Simulations s = MedianBiasOnly(d);
  const NoiseEstimate n = EstimateNoise(d, s);
  return EstimatePlacement(d, s, n, std::vector<char>(d.num_cells(), 1), 0.05);
}

// Placement: every test point of a 2 lights × 4 distances × 4 angles table shifted by a draw of
// τ(D) = 0.05 m + 2 % of D, its four recordings (presets, emitter) sharing it, over replicate
// noise of 5 mm; one test point set 3 m farther (eight times the law there). REML finds the law
// within a factor of two at 16 m and flags that test point, reading far.
TEST(Placement, RemlFindsTheScatterLawAndFlagsTheMisplacedPoint) {
  std::vector<records::PanelMetrics> rows = ArticleGrid();
  std::mt19937 rng(7);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::map<std::string, double> shift;
  for (auto& r : rows) {
    const std::string key = r.light + std::to_string(r.distance_m) + std::to_string(r.angle_deg);
    if (!shift.count(key)) shift[key] = (0.05 + 0.02 * r.distance_m) * unit(rng);
    if (r.light == "sunset" && r.distance_m == 12 && r.angle_deg == 20) shift[key] = 3.0;
    r.median_m = r.distance_m + shift[key] + 0.005 * unit(rng);
  }
  const PlacementEstimate pe = PlacementOf(rows);
  ASSERT_EQ(pe.num_points, 32);
  const double law16 = pe.Law(0, kMedianBias, 16);
  EXPECT_GT(law16, 0.5 * 0.37) << pe.a[0] << " + " << pe.b[0] << "·D";
  EXPECT_LT(law16, 2.0 * 0.37) << pe.a[0] << " + " << pe.b[0] << "·D";
  // The misplaced point is flagged reading far, alone: not its partner of the other light (the
  // fixed effects hold distance × angle as two laws in D·(1 − cos α), not a table that would
  // leave a test point only its contrast with that partner), nor the other test points of its
  // light and distance that it pulls while it is in the fit. Its departure is read from the
  // others.
  bool found = false;
  int flagged = 0;
  for (int t = 0; t < pe.num_points; ++t) {
    if (!pe.flagged[0][t]) continue;
    ++flagged;
    EXPECT_EQ(pe.point_distance_m[t], 12);
    EXPECT_EQ(pe.point_angle_deg[t], 20);
    if (pe.point_light[t] != "sunset") continue;
    found = true;
    EXPECT_NEAR(pe.departure[0][t], 3.0, 0.5);
    EXPECT_GE(pe.tau[0][t], pe.departure[0][t]);  // its own departure as its scatter
  }
  EXPECT_TRUE(found);
  EXPECT_EQ(flagged, 1);
}

// Camera laws acting through the panel's depth D·cos α are fixed effects, not scatter: on a
// table of the article's grid under placement scatter (0.05 m + 2 % of D), a range read as
// depth, D·(1 − cos α) (2.9 m at 16 m and 35°), and a disparity offset's law,
// 0.9 m·(D·cos α / 16 m)², leave the law within 10 % and every flag as it was. Without the
// distance × angle columns, their departure from additive in distance and angle (about ±0.5 m
// at 16 m) would be counted as scatter. (A law of one light only, such as a sunset-only offset,
// departs in light × distance × angle and is partly counted as scatter.)
TEST(Placement, LawsThroughTheDepthAreFixedEffectsNotScatter) {
  const auto table = [](bool laws) {
    std::vector<records::PanelMetrics> rows = ArticleGrid();
    std::mt19937 rng(11);
    std::normal_distribution<double> unit(0.0, 1.0);
    std::map<std::string, double> shift;
    for (auto& r : rows) {
      const std::string key =
          r.light + std::to_string(r.distance_m) + std::to_string(r.angle_deg);
      if (!shift.count(key)) shift[key] = (0.05 + 0.02 * r.distance_m) * unit(rng);
      const double c = std::cos(r.angle_deg * M_PI / 180.0);
      double law = 0;
      if (laws) {
        law += r.distance_m * (1 - c);
        law += 0.9 * std::pow(r.distance_m * c / 16.0, 2);
      }
      r.median_m = r.distance_m + shift[key] + law + 0.005 * unit(rng);
    }
    return PlacementOf(rows);
  };
  const PlacementEstimate plain = table(false), with = table(true);
  for (double dist : {4.0, 16.0}) {
    const double a = plain.Law(0, kMedianBias, dist), b = with.Law(0, kMedianBias, dist);
    EXPECT_NEAR(b, a, 0.1 * a) << dist << " m: " << with.a[0] << " + " << with.b[0] << "·D";
  }
  for (int t = 0; t < with.num_points; ++t)
    EXPECT_EQ(with.flagged[0][t], plain.flagged[0][t]) << t;
}

// A user's unit: one light, one preset, 16 test points × emitter off/on (32 rows), every test
// point shifted by a draw of τ = 2 % of D. Distance × angle would give every test point a fixed
// effect of its own and leave the scatter nothing to be estimated from (REML then ran off to
// 6 m at every distance on such a unit); it is left out there. A misplaced point spills a
// quarter of its departure into its row's and its column's effects and inflates the law, so it
// is also judged left out of the fit.
std::vector<records::PanelMetrics> UnitRows(std::uint32_t seed, bool misplaced) {
  std::vector<records::PanelMetrics> rows;
  for (double a : {0.0, 10.0, 20.0, 35.0})
    for (double dist : {4.0, 8.0, 12.0, 16.0})
      for (const char* emitter : {"off", "on"})
        rows.push_back(Row(dist, a, "HA", emitter, "daylight"));
  std::mt19937 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::map<std::string, double> shift;
  for (auto& r : rows) {
    const std::string key = std::to_string(r.distance_m) + std::to_string(r.angle_deg);
    if (!shift.count(key)) shift[key] = 0.02 * r.distance_m * unit(rng);
    if (misplaced && r.distance_m == 8 && r.angle_deg == 10) shift[key] = 2.0;
    r.median_m = r.distance_m + shift[key] + 0.005 * unit(rng);
  }
  return rows;
}

PlacementEstimate UnitPlacement(std::uint32_t seed, bool misplaced) {
  return PlacementOf(UnitRows(seed, misplaced));
}

TEST(Placement, AUnitOfOneLightAndOnePresetStillEstimatesTheScatter) {
  const PlacementEstimate pe = UnitPlacement(20261124, true);
  ASSERT_EQ(pe.num_points, 16);
  const double law16 = pe.Law(0, kMedianBias, 16);
  EXPECT_GT(law16, 0.5 * 0.32) << pe.a[0] << " + " << pe.b[0] << "·D";
  EXPECT_LT(law16, 2.0 * 0.32) << pe.a[0] << " + " << pe.b[0] << "·D";
  int flagged = 0;
  for (int t = 0; t < pe.num_points; ++t) {
    if (!pe.flagged[0][t]) continue;
    ++flagged;
    EXPECT_EQ(pe.point_distance_m[t], 8);
    EXPECT_EQ(pe.point_angle_deg[t], 10);
    EXPECT_GT(pe.departure[0][t], 1.0);
  }
  EXPECT_EQ(flagged, 1);
}

// A spread's placement scatter is at least what the median's law does to it through the
// simulation: the base placed 2 % further moves log plane_std by 2·0.02 (a spread ∝ Z²), so
// with the medians of a unit scattered by 2 % of D and log plane_std matching the base at every
// test point (its own REML: no scatter), its scatter is |2/D|·τ_median(D), 0.04 at 16 m; with
// no such simulation, none.
TEST(Placement, ASpreadsScatterIsAtLeastWhatThePlacementLawDoesToIt) {
  Design d;
  std::string why;
  ASSERT_TRUE(BuildDesign(UnitRows(20261127, false), &d, &why)) << why;
  Simulations s = MedianBiasOnly(d);
  const NoiseEstimate n = EstimateNoise(d, s);
  const int kk = d.num_metrics();
  const int plane = static_cast<int>(
      std::find(d.metrics.begin(), d.metrics.end(), kPlaneStd) - d.metrics.begin());
  ASSERT_LT(plane, kk);
  const std::vector<char> all(d.num_cells(), 1);
  const PlacementEstimate without = EstimatePlacement(d, s, n, all, 0.05);
  EXPECT_EQ(without.Floor(plane, 16), 0.0);
  s.moved = s.base;
  s.moved_rel = 0.02;
  for (int c = 0; c < d.num_cells(); ++c) s.moved[static_cast<size_t>(c) * kk + plane] += 0.04;
  const PlacementEstimate pe = EstimatePlacement(d, s, n, all, 0.05);
  for (double dist : {4.0, 16.0}) {
    const double expected = 2 / dist * pe.Law(0, kMedianBias, dist);
    EXPECT_NEAR(pe.Floor(plane, dist), expected, 1e-9 + 1e-6 * expected) << dist;
    EXPECT_GE(pe.Law(plane, kPlaneStd, dist), expected) << dist;
    EXPECT_GT(expected, without.Law(plane, kPlaneStd, dist)) << dist;
  }
  EXPECT_NEAR(pe.Floor(plane, 16), 0.04, 0.02);
  for (int t = 0; t < pe.num_points; ++t)
    EXPECT_GE(pe.tau[plane][t], pe.Floor(plane, pe.point_distance_m[t]) - 1e-12);
}

// One displacement of the panel moves each preset's spread by its own sensitivity (on the
// simulator's daylight cells at 12 m, 0.16 per metre for HA and 0.03 for HD). The article's grid
// with every test point displaced by 2 % of D (rng seed 29), log plane_std departing by s·u,
// s = 2/D for HA and 0.4/D for HD, over 3 mm of replicate noise; the base placed 2 % further
// reads the same sensitivities. Each recording's scatter carries its preset's loading (HA five
// times HD's, their mean the test point's τ), and the dispersion about the base reads the
// recordings' departures about the shared displacement at the replicate noise. With one
// loading for every recording of a test point, the HA − HD contrast reads as replicate noise
// many times the twins', and so it does with the presets' simulated sensitivities swapped.
TEST(Placement, EachPresetsSpreadTakesThePanelsDisplacementByItsOwnSensitivity) {
  std::vector<records::PanelMetrics> rows = ArticleGrid();
  std::mt19937 rng(29);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::map<std::string, double> shift;
  auto sensitivity = [](const std::string& preset, double dist) {
    return (preset == "HA" ? 2.0 : 0.4) / dist;
  };
  for (auto& r : rows) {
    const std::string key = r.light + std::to_string(r.distance_m) + std::to_string(r.angle_deg);
    if (!shift.count(key)) shift[key] = 0.02 * r.distance_m * unit(rng);
    r.median_m = r.distance_m + shift[key] + 0.005 * unit(rng);
    r.mean_m = r.median_m + 0.01;
    r.plane_std_m =
        0.05 * std::exp(sensitivity(r.preset, r.distance_m) * shift[key] + 0.003 * unit(rng));
  }
  Design d;
  std::string why;
  ASSERT_TRUE(BuildDesign(rows, &d, &why)) << why;
  Simulations s = MedianBiasOnly(d);
  const int kk = d.num_metrics();
  const int plane = static_cast<int>(
      std::find(d.metrics.begin(), d.metrics.end(), kPlaneStd) - d.metrics.begin());
  ASSERT_LT(plane, kk);
  s.moved_rel = 0.02;
  for (int c = 0; c < d.num_cells(); ++c) {
    const size_t o = static_cast<size_t>(c) * kk + plane;
    s.base[o] = std::log(0.05);
  }
  s.moved = s.base;
  for (int c = 0; c < d.num_cells(); ++c)
    s.moved[static_cast<size_t>(c) * kk + plane] +=
        0.02 * d.cells[c].distance_m * sensitivity(d.cells[c].preset, d.cells[c].distance_m);
  const NoiseEstimate n = EstimateNoise(d, s);
  const std::vector<char> all(d.num_cells(), 1);
  PlacementEstimate pe = EstimatePlacement(d, s, n, all, 0.05);
  ASSERT_EQ(pe.tau_cell[plane].size(), static_cast<size_t>(d.num_cells()));
  int pairs = 0;
  for (int a = 0; a < d.num_cells(); ++a)
    for (int b = 0; b < d.num_cells(); ++b) {
      if (pe.point[a] != pe.point[b] || d.cells[a].preset != "HA" || d.cells[b].preset != "HD")
        continue;
      const double tau = pe.tau[plane][pe.point[a]];
      EXPECT_NEAR(pe.Tau(plane, a), 5 * pe.Tau(plane, b), 1e-9 * tau);
      EXPECT_NEAR(pe.Tau(plane, a) + pe.Tau(plane, b), 2 * tau, 1e-9 * tau);
      ++pairs;
    }
  EXPECT_EQ(pairs, 4 * 32);  // two HA and two HD recordings at each of the 32 test points
  const GapModel model(d, s, n, FitSettings(), &pe);
  const std::vector<double> loaded = Dispersion(model, s.base, all);
  pe.tau_cell[plane].clear();  // one loading: every recording at the test point's τ
  const GapModel one(d, s, n, FitSettings(), &pe);
  const std::vector<double> shared = Dispersion(one, s.base, all);
  std::printf("log plane_std: phi %.2f psi %.2f with each preset's loading; phi %.2f psi %.2f "
              "with one\n",
              loaded[plane], loaded[kk + plane], shared[plane], shared[kk + plane]);
  EXPECT_LT(loaded[plane], 1.6);
  EXPECT_GT(shared[plane], 5.0);
  // The loadings come from the simulation, not from the table: a simulation whose presets
  // respond the other way round (HA 0.4/D, HD 2/D) gives loadings the table does not follow,
  // and the recordings' departures about the shared displacement read as noise again.
  for (int c = 0; c < d.num_cells(); ++c)
    s.moved[static_cast<size_t>(c) * kk + plane] =
        s.base[static_cast<size_t>(c) * kk + plane] +
        0.02 * d.cells[c].distance_m *
            sensitivity(d.cells[c].preset == "HA" ? "HD" : "HA", d.cells[c].distance_m);
  const PlacementEstimate swapped = EstimatePlacement(d, s, n, all, 0.05);
  const GapModel wrong(d, s, n, FitSettings(), &swapped);
  const std::vector<double> misloaded = Dispersion(wrong, s.base, all);
  std::printf("log plane_std: phi %.2f with the presets' loadings swapped\n", misloaded[plane]);
  EXPECT_GT(misloaded[plane], 5.0);
}

// The same units without a misplaced point, 20 seeds: the test at p < 0.05 / 16 flags a point in
// few of them (at most 3 of 20), and the law stays within a factor of two at 16 m in most.
TEST(Placement, AUnitWithoutAMisplacedPointIsRarelyFlagged) {
  int tables_flagged = 0, law_ok = 0;
  for (std::uint32_t seed = 1; seed <= 20; ++seed) {
    const PlacementEstimate pe = UnitPlacement(seed, false);
    int f = 0;
    for (int t = 0; t < pe.num_points; ++t) f += pe.flagged[0][t];
    tables_flagged += f > 0;
    const double law16 = pe.Law(0, kMedianBias, 16);
    law_ok += law16 > 0.16 && law16 < 0.64;
  }
  std::printf("unit without a misplaced point: a point flagged in %d of 20 tables, the law at 16 m "
              "within a factor of two in %d of 20\n", tables_flagged, law_ok);
  EXPECT_LE(tables_flagged, 3);
  EXPECT_GE(law_ok, 16);
}

// A unit of 16 test points whose draws leave the law's growth in distance hard to read: the
// departures of one table without effect made by the simulator (placement 2 % of D, truth seed
// 10⁹ + 94), over 5 mm of replicate noise. Fitted there, the law reads about 0.07 m at every
// distance (0.32 m at 16 m in truth); the 16 m, 10° point, +0.32 m beside −0.19 to −0.40 m
// (0.9 σ of its own true draw), stands out of it. The other 15 points bound the scatter at
// 16 m near 0.14 m (TauUpper), so it is still flagged, as one table in twenty may be (the
// Bonferroni bound, 2.96), but its z is read at that bound: 3.9, p 1e-4 (6.1 and p 1e-9 at the
// fitted law alone, as it was).
TEST(Placement, AFlaggedPointIsReadAtTheLargestScatterTheLawAllows) {
  const std::map<double, std::map<double, double>> departs = {
      {4, {{0, -0.005}, {10, 0.024}, {20, -0.003}, {35, 0.021}}},
      {8, {{0, 0.142}, {10, 0.061}, {20, -0.119}, {35, 0.087}}},
      {12, {{0, 0.012}, {10, -0.235}, {20, -0.285}, {35, -0.199}}},
      {16, {{0, -0.187}, {10, 0.317}, {20, -0.399}, {35, -0.222}}}};
  std::vector<records::PanelMetrics> rows = UnitRows(20261201, false);
  std::mt19937 rng(5);
  std::normal_distribution<double> unit(0.0, 1.0);
  for (auto& r : rows)
    r.median_m = r.distance_m + departs.at(r.distance_m).at(r.angle_deg) + 0.005 * unit(rng);
  const PlacementEstimate pe = PlacementOf(rows);
  for (int t = 0; t < pe.num_points; ++t) {
    const bool far_point = pe.point_distance_m[t] == 16 && pe.point_angle_deg[t] == 10;
    EXPECT_EQ(pe.flagged[0][t] != 0, far_point) << TestPointName(pe, t);
    if (!far_point) continue;
    const double law = pe.Law(0, kMedianBias, 16);
    EXPECT_LT(law, 0.1);
    EXPECT_NEAR(pe.departure[0][t], 0.6, 0.05);
    EXPECT_GT(pe.departure_z[0][t], 2.96);
    EXPECT_LT(pe.departure_z[0][t], 5.0)
        << "z " << pe.departure_z[0][t] << " under " << pe.a[0] << " + " << pe.b[0] << "·D";
  }
}

TEST(Localize, AGapAlongOneFactorIsThatFactors) {
  Design d;
  std::string why;
  ASSERT_TRUE(BuildDesign(Table(), &d, &why)) << why;
  const int k_count = d.num_metrics();
  std::vector<double> z(d.real.size(), 0.0);
  for (int c = 0; c < d.num_cells(); ++c) {
    z[c * k_count + 0] = d.cells[c].distance_m == 12 ? 5.0 : -2.5;  // distance only, mean 0
    z[c * k_count + 1] = d.cells[c].preset == "HD" ? 3.0 : 1.0;     // offset 2, preset ±1
  }
  const Localization loc = Localize(d, z, 0.05);
  auto share = [&](int k, const std::string& term) {
    for (size_t t = 0; t < loc.terms.size(); ++t)
      if (loc.terms[t] == term) return loc.metric_pct[k][t];
    return -1.0;
  };
  EXPECT_NEAR(share(0, "distance"), 100, 1e-6);
  EXPECT_NEAR(share(1, "offset"), 80, 1e-6);  // 2² of 2² + 1²
  EXPECT_NEAR(share(1, "preset"), 20, 1e-6);
  EXPECT_NEAR(share(1, "rest"), 0, 1e-6);
  EXPECT_NEAR(loc.metric_share_pct[2], 0, 1e-9);
  // χ² on 4 metrics: 6.25 + 1 or 9 elsewhere is not significant at 0.05/48 (χ²₄ > 18.4);
  // 25 + 1 or 9 at 12 m is.
  EXPECT_EQ(loc.significant.size(), 16u);
  for (const CellGap& g : loc.significant) EXPECT_EQ(d.cells[g.cell].distance_m, 12);
}

// The rest of the gap (unexplained.h) of a 2 lights × 4 distances × 4 angles × 2 presets × 2
// emitter table whose simulation reads every metric but the median bias as the real one and the
// median bias as 0 (the model's prediction): each test point set off by a heavy-tailed draw
// (Student t, 3 degrees of freedom) of τ(D) = 0.05 m + 2 % of D over 5 mm of replicate noise,
// plus what a case adds to a row.
struct RestTable {
  Design d;
  Simulations s;
  NoiseEstimate n;
  PlacementEstimate pe;
};

RestTable RestTableOf(std::uint32_t seed,
                      const std::function<double(const records::PanelMetrics&)>& add,
                      bool heavy_tailed) {
  std::vector<records::PanelMetrics> rows = ArticleGrid();
  std::mt19937 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::student_t_distribution<double> heavy(3.0);
  std::map<std::string, double> shift;
  for (auto& r : rows) {
    const std::string key = r.light + std::to_string(r.distance_m) + std::to_string(r.angle_deg);
    if (!shift.count(key))
      shift[key] = (0.05 + 0.02 * r.distance_m) * (heavy_tailed ? heavy(rng) : unit(rng));
    r.median_m = r.distance_m + shift[key] + add(r) + 0.005 * unit(rng);
  }
  RestTable t;
  std::string why;
  if (!BuildDesign(rows, &t.d, &why)) throw std::runtime_error(why);
  t.s = MedianBiasOnly(t.d);
  t.n = EstimateNoise(t.d, t.s);
  t.pe = EstimatePlacement(t.d, t.s, t.n, std::vector<char>(t.d.num_cells(), 1), 0.05);
  return t;
}

std::vector<Unexplained> RestOf(std::uint32_t seed,
                                const std::function<double(const records::PanelMetrics&)>& add,
                                std::vector<std::string>* flagged = nullptr,
                                bool heavy_tailed = true) {
  const RestTable table = RestTableOf(seed, add, heavy_tailed);
  const Design& d = table.d;
  const Simulations& s = table.s;
  const NoiseEstimate& n = table.n;
  const PlacementEstimate& pe = table.pe;
  for (int t = 0; t < pe.num_points && flagged; ++t)
    if (pe.flagged[0][t])
      flagged->push_back(pe.point_light[t] + " " + std::to_string(pe.point_distance_m[t]) + " " +
                         std::to_string(pe.point_angle_deg[t]));
  const GapModel model(d, s, n, FitSettings(), &pe);
  return DescribeRest(model, s.base, pe, RestParams());
}

// Heavy-tailed placement alone, 10 tables: the permutation test describes a group in at most one
// (its level is 0.05 / metrics per metric): heavy tails and the placement a test point's
// recordings share are the reference, not a normal law (the χ² test alone describes a group in
// 4 of these 10).
TEST(Rest, HeavyTailedPlacementAloneIsRarelyDescribed) {
  int described = 0;
  for (std::uint32_t seed = 101; seed <= 110; ++seed) {
    const auto rest = RestOf(seed, [](const records::PanelMetrics&) { return 0.0; });
    bool any = false;
    for (const Unexplained& u : rest) {
      EXPECT_EQ(u.metric, "median_bias_m") << "the other metrics have no gap";
      any = any || !u.beyond_placement_law;
    }
    described += any;
  }
  std::printf("heavy-tailed placement alone: a group described in %d of 10 tables\n", described);
  EXPECT_LE(described, 1);
}

// A camera effect beside that placement: every sunset recording reads 0.4 m far (a sunset-only
// offset, about twice the law at 8 m). The rest names the sunset light (alone or with another
// factor) and sizes it within its standard error; a test point set 3 m off is listed too, and
// not its partner of the other light.
TEST(Rest, ASunsetOnlyOffsetIsNamedAndSizedAndAMisplacedPointListed) {
  const auto rest = RestOf(202, [](const records::PanelMetrics& r) {
    double v = r.light == "sunset" ? 0.4 : 0.0;
    if (r.light == "daylight" && r.distance_m == 8 && r.angle_deg == 10) v += 3.0;
    return v;
  });
  bool sunset = false, point = false;
  for (const Unexplained& u : rest) {
    ASSERT_EQ(u.metric, "median_bias_m");
    if (u.where.find("test point daylight 8 m 10") != std::string::npos) {
      point = true;
      EXPECT_TRUE(u.beyond_placement_law);
      EXPECT_NEAR(u.size, 3.0, 3 * u.size_se) << u.where;  // from its row's other test points
      continue;
    }
    // The placement estimate sees the point against its partner of the other light, flagged
    // with it the other way (placement.h); the partner is not the misplaced one.
    EXPECT_EQ(u.where.find("test point sunset 8 m 10"), std::string::npos) << u.where;
    if (u.beyond_placement_law) continue;
    EXPECT_NE(u.where.find("sunset"), std::string::npos) << u.where;
    sunset = sunset || u.where.find("sunset") != std::string::npos;
    EXPECT_LT(u.p_value, 0.01);
    EXPECT_NEAR(u.size, 0.4, std::max(0.1, 3 * u.size_se)) << u.where << " ± " << u.size_se;
  }
  EXPECT_TRUE(sunset);
  EXPECT_TRUE(point);
}

// A test point read 1 m far (daylight, 8 m, 10°) under normal placement scatter (0.05 m + 2 %
// of D: 0.21 m at 8 m), 20 tables. Distance × angle is two laws in D·(1 − cos α), not a table
// of its own, so the point is seen against its light's and its distance's other test points,
// not only against its partner of the other light: the partner is never flagged, the point is
// in most tables (p < 0.05 / 32 for a departure of about five times the law: not every table),
// and the rest names it where it is flagged, sized from its row's other test points.
TEST(Rest, AMisplacedPointIsFlaggedAloneAndNamed) {
  int own = 0, partner = 0, named = 0;
  for (std::uint32_t seed = 301; seed <= 320; ++seed) {
    std::vector<std::string> flagged;
    const auto rest = RestOf(
        seed,
        [](const records::PanelMetrics& r) {
          return r.light == "daylight" && r.distance_m == 8 && r.angle_deg == 10 ? 1.0 : 0.0;
        },
        &flagged, false);
    const auto is = [&](const std::string& light) {
      return std::count(flagged.begin(), flagged.end(),
                        light + " " + std::to_string(8.0) + " " + std::to_string(10.0)) > 0;
    };
    own += is("daylight");
    partner += is("sunset");
    for (const Unexplained& u : rest) {
      EXPECT_EQ(u.where.find("test point sunset 8 m 10"), std::string::npos)
          << "seed " << seed << ": " << u.where << " " << u.size;
      if (u.where.find("test point daylight 8 m 10") == std::string::npos) continue;
      ++named;
      EXPECT_NEAR(u.size, 1.0, 3 * u.size_se) << "seed " << seed;
    }
  }
  std::printf("1 m at one test point: flagged in %d of 20 tables, its partner in %d, named in %d\n",
              own, partner, named);
  EXPECT_EQ(partner, 0);
  EXPECT_GE(own, 10);
  EXPECT_GE(named, own);
}

// A far over-read at the far end only: every recording at 16 m reads 0.5 m far (1.35 times the
// placement law there, 0.37 m), nothing nearer, under normal placement scatter, 40 tables. At
// that size the rest names it in about half of them: named at 16 m (the 16 m recordings, or a
// step from 16 m) in 21 (22 before each light's laws were tested with the shared ones, whose
// maximum the drawn signs are held against), other cells named once, and without the
// over-read (the same draws) a group described in 1. The group search reads the share of Σz² a
// group's mean explains; weighted by the group's smallness, as it was, it named 16 m in 19 (it
// prefers 16 m × one angle, two test points, whose best the permuted tables often match).
// Without the χ² gate on the median's whole Σz² it would be named in 24: the misses are mostly
// power.
TEST(Rest, AFarOverReadAtTheFarEndAloneIsNamedThere) {
  int named = 0, elsewhere = 0, null_described = 0;
  for (std::uint32_t seed = 801; seed <= 840; ++seed) {
    const auto far = RestOf(
        seed, [](const records::PanelMetrics& r) { return r.distance_m == 16 ? 0.5 : 0.0; },
        nullptr, false);
    bool at_16 = false;
    for (const Unexplained& u : far) {
      if (u.beyond_placement_law) continue;
      const bool there = u.where == "distance 16 m" || u.where == "distance ≥ 16 m";
      at_16 = at_16 || there;
      elsewhere += !there;
    }
    named += at_16;
    const auto null = RestOf(seed, [](const records::PanelMetrics&) { return 0.0; }, nullptr,
                             false);
    null_described += std::any_of(null.begin(), null.end(), [](const Unexplained& u) {
      return !u.beyond_placement_law;
    });
  }
  std::printf("0.5 m far at 16 m only: named at 16 m in %d of 40 tables, other groups named %d "
              "times; without it a group described in %d of 40\n",
              named, elsewhere, null_described);
  EXPECT_GE(named, 20);
  EXPECT_LE(elsewhere, 2);
  EXPECT_LE(null_described, 2);
}

// The step rule (MedianStepFrom) under normal placement scatter (0.05 m + 2 % of D), 40 tables
// each. An offset at sunset only (0.15 px: 0.63 m far at 16 m, ∝ D², nothing in daylight) is a
// smooth law in one light: a step is named for it in 1 of these 40. Pooled over both lights it
// reads as a step, and a rule that held the step against the laws over the whole table alone
// named one in 5. A far over-read of 0.5 m from 8 m on in every light is still named a step from
// 8 m (38 of 40 either way).
TEST(Rest, ALawInOneLightIsNotAStepAndAStepStillIs) {
  auto steps = [](std::uint32_t first,
                  const std::function<double(const records::PanelMetrics&)>& add,
                  double* at_8) {
    int named = 0;
    *at_8 = 0;
    for (std::uint32_t seed = first; seed < first + 40; ++seed) {
      const RestTable t = RestTableOf(seed, add, false);
      const GapModel model(t.d, t.s, t.n, FitSettings(), &t.pe);
      const double from = MedianStepFrom(model, t.s.base, t.pe,
                                         std::vector<char>(t.d.num_cells(), 1), RestParams());
      named += std::isfinite(from);
      *at_8 += from == 8;
    }
    return named;
  };
  double sunset_at_8 = 0, far_at_8 = 0;
  const int sunset = steps(
      401,
      [](const records::PanelMetrics& r) {
        return r.light == "sunset" ? 0.15 * r.distance_m * r.distance_m / 60.8 : 0.0;
      },
      &sunset_at_8);
  const int far = steps(
      601, [](const records::PanelMetrics& r) { return r.distance_m >= 8 ? 0.5 : 0.0; },
      &far_at_8);
  std::printf("a step named: sunset-only offset in %d of 40 tables, far step from 8 m in %d "
              "(from 8 m in %g)\n", sunset, far, far_at_8);
  EXPECT_LE(sunset, 2);
  EXPECT_GE(far_at_8, 36);
}

// The rest's description of a law in one light (DescribeRest, SharedDepartureP's laws per
// light). An offset at sunset only (0.15 px: 0.63 m far at 16 m, ∝ D², nothing in daylight),
// under normal placement scatter, 40 tables: the rest names the sunset light in at least 28
// (29 measured; 13 before each light's laws were tested), at least 16 of them by a law in
// distance (∝ D or ∝ D²), and other cells in at most 4. A far over-read of 0.5 m from 8 m on in
// every light (the case built to break it: half its cells are one light's) is named over both
// lights in at least 36 and never as one light.
TEST(Rest, ALawInOneLightIsNamedInThatLight) {
  auto describe = [](std::uint32_t first,
                     const std::function<double(const records::PanelMetrics&)>& add,
                     std::map<std::string, int>* where) {
    for (std::uint32_t seed = first; seed < first + 40; ++seed) {
      const auto rest = RestOf(seed, add, nullptr, false);
      for (const Unexplained& u : rest)
        if (!u.beyond_placement_law) ++(*where)[u.where + " (" + u.form + ")"];
    }
  };
  std::map<std::string, int> sunset, far;
  describe(
      1401,
      [](const records::PanelMetrics& r) {
        return r.light == "sunset" ? 0.15 * r.distance_m * r.distance_m / 60.8 : 0.0;
      },
      &sunset);
  describe(
      1601, [](const records::PanelMetrics& r) { return r.distance_m >= 8 ? 0.5 : 0.0; }, &far);
  int in_sunset = 0, as_law = 0, elsewhere = 0, far_named = 0, far_in_one_light = 0;
  for (const auto& [w, count] : sunset) {
    std::printf("sunset-only offset, 40 tables: %s in %d\n", w.c_str(), count);
    (w.find("sunset") != std::string::npos ? in_sunset : elsewhere) += count;
    as_law += w.rfind("light sunset (∝ D", 0) == 0 ? count : 0;
  }
  for (const auto& [w, count] : far) {
    std::printf("far step from 8 m, 40 tables: %s in %d\n", w.c_str(), count);
    (w.rfind("light ", 0) == 0 ? far_in_one_light : far_named) += count;
  }
  EXPECT_GE(in_sunset, 28);
  EXPECT_GE(as_law, 16);
  EXPECT_LE(elsewhere, 4);
  EXPECT_GE(far_named, 36);
  EXPECT_EQ(far_in_one_light, 0);
}

// Detection limits (limits.h) against the fit itself. A 2 lights × 4 distances × 4 angles table
// under placement scatter (0.05 m + 2 % of D) and 5 mm of replicate noise, one candidate that
// moves the median by −δ·D²/60.8 (a disparity offset's law) and a calibration direction ∝ D that
// can take part of it. The limit found in closed form (the whitened departure with the
// calibration projected out) is checked by fitting: on a table that reads the base plus the
// departure at the limit, noise-free, the calibrated base's deviance less the candidate's is
// the noncentrality asked, (√(ln n) + Φ⁻¹(0.8))², and the fit finds the limit's size. The
// share-of-the-gap bar is checked against the folds' gains computed apart. Without placement
// scatter the limit is smaller; with the calibration free to move it is larger than with the
// calibration held.
struct LimitTable {
  Design d;
  Simulations s;
  NoiseEstimate n;
  PlacementEstimate pe;
};

double OffsetLaw(double delta, double distance_m) {
  return -delta * distance_m * distance_m / 60.8;
}

// The article's grid, every test point placed by τ(D) = 0.05 m + 2 % of D, over 5 mm of replicate
// noise (draws of `seed`); each row's median moved by `extra` too, when given.
std::vector<records::PanelMetrics> PlacedGrid(
    std::uint32_t seed, const std::function<double(const records::PanelMetrics&)>& extra) {
  std::vector<records::PanelMetrics> rows = ArticleGrid();
  std::mt19937 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::map<std::string, double> shift;
  for (auto& r : rows) {
    const std::string key = r.light + std::to_string(r.distance_m) + std::to_string(r.angle_deg);
    if (!shift.count(key)) shift[key] = (0.05 + 0.02 * r.distance_m) * unit(rng);
    r.median_m = r.distance_m + shift[key] + 0.005 * unit(rng);
    if (extra) r.median_m += extra(r);
  }
  return rows;
}

// The rows against a simulation of the median bias alone (MedianBiasOnly; the calibration's σ_d
// moving the median by 0.02·D), with one candidate whose surface adds law(its node's values, D)
// to the median; their noise and placement estimated.
LimitTable MedianTable(const std::vector<records::PanelMetrics>& rows, const Candidate& candidate,
                       const std::function<double(const std::vector<double>&, double)>& law) {
  LimitTable t;
  std::string why;
  if (!BuildDesign(rows, &t.d, &why)) throw std::runtime_error(why);
  t.s = MedianBiasOnly(t.d);
  const int kk = t.d.num_metrics();
  t.s.jac_log_sigma.assign(t.s.base.size(), 0.0);
  t.s.jac_logit_p.assign(t.s.base.size(), 0.0);
  Surface surf;
  surf.candidate = candidate;
  const std::vector<Axis>& axes = candidate.axes;
  const int last = static_cast<int>(axes.back().nodes.size());
  surf.num_nodes = static_cast<int>(axes[0].nodes.size()) * (axes.size() == 2 ? last : 1);
  for (int c = 0; c < t.d.num_cells(); ++c)
    for (int k = 0; k < kk; ++k) {
      const size_t o = static_cast<size_t>(c) * kk + k;
      const double dist = t.d.cells[c].distance_m;
      if (k == 0) t.s.jac_log_sigma[o] = 0.02 * dist;
      for (int node = 0; node < surf.num_nodes; ++node) {
        std::vector<double> values{axes[0].nodes[axes.size() == 1 ? node : node / last]};
        if (axes.size() == 2) values.push_back(axes[1].nodes[node % last]);
        surf.table.push_back(t.s.base[o] + (k == 0 ? law(values, dist) : 0));
      }
    }
  t.s.surfaces.push_back(surf);
  t.n = EstimateNoise(t.d, t.s);
  t.pe = EstimatePlacement(t.d, t.s, t.n, std::vector<char>(t.d.num_cells(), 1), 0.05);
  return t;
}

// PlacedGrid's rows against a disparity offset's surface; with `delta_px`, each row's median
// also departs by an offset of that size.
LimitTable MakeLimitTable(
    std::uint32_t seed,
    const std::function<double(const records::PanelMetrics&)>& delta_px = nullptr) {
  Candidate offset = DefaultCandidates()[0];
  offset.range_law = false;  // the law as given, not averaged over placement
  EXPECT_EQ(offset.effect, "disparity_offset");
  return MedianTable(
      PlacedGrid(seed,
                 delta_px ? std::function<double(const records::PanelMetrics&)>(
                                [&](const records::PanelMetrics& r) {
                                  return OffsetLaw(delta_px(r), r.distance_m);
                                })
                          : nullptr),
      offset, [](const std::vector<double>& v, double dist) { return OffsetLaw(v[0], dist); });
}

// An effect's interval counts a test point once (robust_covariance.h, through FitTerms): on
// PlacedGrid's rows, whose four recordings of a test point share its placement draw, with the
// placement scatter taken as 0 (the model then weighs each recording as independent), a shared
// offset's interval over test points (the placement estimate's units) is about √4 times as wide
// as over recordings (no placement estimate: each recording its own unit). The fit is the same.
TEST(RobustCovariance, AnEffectsIntervalCountsATestPointOnce) {
  const LimitTable t = MakeLimitTable(9, [](const records::PanelMetrics&) { return 0.2; });
  PlacementEstimate no_scatter = t.pe;
  for (auto& row : no_scatter.tau) std::fill(row.begin(), row.end(), 0.0);
  FitSettings fs;
  fs.huber_k = 0;
  const std::vector<char> all(t.d.num_cells(), 1);
  auto width = [&](const PlacementEstimate* pe, double* value) -> double {
    const GapModel model(t.d, t.s, t.n, fs, pe);
    const ModelFit f = FitCandidate(model, 0, Scope::kShared, all);
    EXPECT_TRUE(f.success) << f.message;
    if (!f.success) return NAN;
    *value = f.terms[0].values[0][0];
    return f.terms[0].ci_hi[0][0] - f.terms[0].ci_lo[0][0];
  };
  double by_point_value = 0, by_recording_value = 1;
  const double by_point = width(&no_scatter, &by_point_value);
  const double by_recording = width(nullptr, &by_recording_value);
  std::printf("offset %.4f px: interval width over test points %.4f, over recordings %.4f\n",
              by_point_value, by_point, by_recording);
  EXPECT_NEAR(by_point_value, by_recording_value, 1e-9);
  EXPECT_GT(by_point, 1.5 * by_recording);
  EXPECT_LT(by_point, 3.0 * by_recording);
}

// Scopes (fit.h). An offset of 0.3 px in the sunset rows alone, both presets alike: fitted per
// light it reads about 0 in daylight and its size at sunset, and its BIC is the best of the
// three scopes (per scenario fits as well with two more values). An offset of one preset in both
// lights is not a light's: there per scenario is the best, per light no better than shared. The
// placement draws pull each light's size (at 16 m a test point's 0.37 m is 0.09 px): over seeds 1–12
// per light was the best BIC in all, its two sizes within 20 % of 0.3 px in 11 (seed 2's
// daylight read −0.062 px; seed 47's +0.094); this runs seed 4.
TEST(Scope, AnEffectOfOneLightIsFittedPerLight) {
  const double delta = 0.3;
  for (int by_preset = 0; by_preset < 2; ++by_preset) {
    SCOPED_TRACE(by_preset ? "HD only" : "sunset only");
    const LimitTable t = MakeLimitTable(4, [&](const records::PanelMetrics& r) {
      return (by_preset ? r.preset == "HD" : r.light == "sunset") ? delta : 0.0;
    });
    ASSERT_EQ(t.d.num_lights(), 2);
    ASSERT_EQ(ScopeGroups(t.d, Scope::kPerLight), 2);
    ASSERT_EQ(ScopeGroups(t.d, Scope::kPerScenario), 4);
    ASSERT_TRUE(ScopeApplies(t.d, Scope::kPerLight) && ScopeApplies(t.d, Scope::kPerScenario));
    const int sunset = ScopeGroupName(t.d, Scope::kPerLight, 0) == "sunset" ? 0 : 1;
    EXPECT_EQ(ScopeGroupName(t.d, Scope::kPerLight, sunset), "sunset");
    for (int s = 0; s < t.d.num_scenarios(); ++s) {
      const std::string& name = t.d.scenario_names[s];
      EXPECT_EQ(ScopeGroupOf(t.d, Scope::kPerLight, s) == sunset, name.rfind("sunset/", 0) == 0)
          << name;
      EXPECT_EQ(ScopeGroupOf(t.d, Scope::kPerScenario, s), s);
      EXPECT_EQ(ScopeGroupOf(t.d, Scope::kShared, s), 0);
    }
    FitSettings fs;
    fs.huber_k = 0;
    const std::vector<char> all(t.d.num_cells(), 1);
    const GapModel model(t.d, t.s, t.n, fs, &t.pe);
    const ModelFit m0 = FitTerms(model, {}, all);
    ASSERT_TRUE(m0.success);
    const ModelFit shared = FitCandidate(model, 0, Scope::kShared, all);
    const ModelFit light = FitCandidate(model, 0, Scope::kPerLight, all, &shared);
    const ModelFit scenario = FitCandidate(model, 0, Scope::kPerScenario, all, &shared);
    ASSERT_TRUE(shared.success && light.success && scenario.success);
    ASSERT_EQ(light.terms[0].values.size(), 2u);
    ASSERT_EQ(scenario.terms[0].values.size(), 4u);
    EXPECT_EQ(light.num_params, 2);
    EXPECT_EQ(scenario.num_params, 4);
    const double log_n = std::log(static_cast<double>(m0.num_obs));
    auto bic = [&](const ModelFit& f) {
      return m0.Deviance() - f.Deviance() - (f.num_params - m0.num_params) * log_n;
    };
    std::printf("%s: BIC shared %.1f, per light %.1f, per scenario %.1f; per light %.3f "
                "[%.3f, %.3f] / %.3f [%.3f, %.3f]\n",
                by_preset ? "HD only" : "sunset only", bic(shared), bic(light), bic(scenario),
                light.terms[0].values[0][0], light.terms[0].ci_lo[0][0],
                light.terms[0].ci_hi[0][0], light.terms[0].values[1][0],
                light.terms[0].ci_lo[1][0], light.terms[0].ci_hi[1][0]);
    if (!by_preset) {
      EXPECT_NEAR(light.terms[0].values[sunset][0], delta, 0.2 * delta);
      EXPECT_NEAR(light.terms[0].values[1 - sunset][0], 0.0, 0.2 * delta);
      EXPECT_GT(bic(light), bic(scenario));
      EXPECT_GT(bic(light), bic(shared));
    } else {
      for (int s = 0; s < t.d.num_scenarios(); ++s) {
        const bool hd = t.d.scenario_names[s].find("/HD") != std::string::npos;
        EXPECT_NEAR(scenario.terms[0].values[s][0], hd ? delta : 0.0, 0.2 * delta)
            << t.d.scenario_names[s];
      }
      EXPECT_GT(bic(scenario), bic(light));
      EXPECT_GT(bic(scenario), bic(shared));
      EXPECT_LT(bic(light), bic(shared) + log_n);  // a second value buys nothing
    }
  }
  // Where per light is per scenario (one preset) or a single group (one light), it is not
  // offered.
  for (const char* keep : {"HA", "daylight"}) {
    std::vector<records::PanelMetrics> rows;
    for (const auto& r : ArticleGrid())
      if (r.preset == keep || r.light == keep) rows.push_back(r);
    Design d;
    std::string why;
    ASSERT_TRUE(BuildDesign(rows, &d, &why)) << why;
    EXPECT_FALSE(ScopeApplies(d, Scope::kPerLight)) << keep;
    EXPECT_TRUE(ScopeApplies(d, Scope::kPerScenario)) << keep;
  }
}

// The one-standard-error rule (BeatsByOneSe) over a table's test points: a wider fit that
// halves every test point's misfit beats the simpler one; one that wins more in total, all of
// it from a single test point, and loses a little in the others, does not (a placement draw,
// not the group: a gain from one unit alone is exactly one standard error of the sum). The
// held-out deviance's parts per test point add up to the whole.
TEST(Scope, AWiderFitMustBeatTheSimplerByOneStandardError) {
  const LimitTable t = MakeLimitTable(5);
  const std::vector<char> all(t.d.num_cells(), 1);
  FitSettings fs;
  fs.huber_k = 0;
  const GapModel model(t.d, t.s, t.n, fs, &t.pe);
  const int kk = model.num_metrics();
  const int point = t.pe.point[0];
  auto miss = [&](double at_point, double elsewhere) {
    HeldOut h;
    h.cells = all;
    h.mu.assign(model.num_obs(), NAN);
    for (int o = 0; o < model.num_obs(); ++o)  // the medians miss by these many noise units
      h.mu[o] = o % kk != 0 ? model.y(o)
                            : model.y(o) - (t.pe.point[o / kk] == point ? at_point : elsewhere) *
                                               model.noise(o);
    return h;
  };
  const HeldOut simpler = miss(10, 1);
  std::map<long long, double> units;
  const double whole = model.DataDeviance(simpler.mu, all, &units);
  double sum = 0;
  for (const auto& kv : units) sum += kv.second;
  EXPECT_NEAR(sum, whole, 1e-9 * whole);
  EXPECT_EQ(units.size(), 32u);  // 2 lights × 4 distances × 4 angles

  const HeldOut even = miss(5, 0.5);
  const HeldOut one = miss(0, 1.02);
  const double even_gain = whole - model.DataDeviance(even.mu, all);
  const double one_gain = whole - model.DataDeviance(one.mu, all);
  std::printf("gap %.2f: the even fit gains %.2f, the one test point's %.2f\n", whole, even_gain,
              one_gain);
  EXPECT_GT(one_gain, even_gain);
  EXPECT_TRUE(BeatsByOneSe(model, even, simpler));
  EXPECT_FALSE(BeatsByOneSe(model, simpler, even));
  EXPECT_FALSE(BeatsByOneSe(model, one, simpler));
}

// A discrete width's interval (ProfileDiscreteAxes) on region_spill's grid (width 0 to 5 px
// discrete, background 1.3 to 3.6 continuous) with surfaces made here, in the median bias alone,
// over the placement and noise of MakeLimitTable. Where the table sees the width and the
// background only through their product (w·(b − 1)·0.02·D), every width from 1 to 5 px fits as
// well as the injected 2 px with its own background (1 px: b = 3.4, 5 px: b = 1.48): the interval
// is [1, 5] whatever width the fit stopped at, and 0 (no effect) stays out. Where the width acts
// as D² and the background as D, no other width is within the profile's 3.84: [2, 2]. The
// interval the fit's curvature gives a discrete axis is its value alone, which fails the first;
// taking every node fails the second; reading the deviances from the width given rather than
// the lowest fails the fit held at 3 px.
TEST(Profile, ADiscreteWidthsIntervalHoldsTheWidthsTheTableCannotTellApart) {
  for (int separable = 0; separable < 2; ++separable) {
    SCOPED_TRACE(separable ? "width ∝ D², background ∝ D" : "width × background");
    auto law = [&](double w, double b, double dist) {
      return separable ? 0.01 * w * dist * dist + 0.04 * (b - 1) * dist
                       : 0.02 * w * (b - 1) * dist;
    };
    Candidate spill;
    for (const Candidate& c : DefaultCandidates())
      if (c.effect == "region_spill") spill = c;
    ASSERT_EQ(spill.effect, "region_spill");
    ASSERT_TRUE(spill.axes[0].discrete);
    ASSERT_EQ(spill.axes[0].nodes.front(), 0.0);
    ASSERT_EQ(spill.axes[0].nodes.back(), 5.0);
    const LimitTable t = MedianTable(
        PlacedGrid(17, [&](const records::PanelMetrics& r) { return law(2, 2.2, r.distance_m); }),
        spill, [&](const std::vector<double>& v, double dist) { return law(v[0], v[1], dist); });
    FitSettings fs;
    fs.huber_k = 0;
    const std::vector<char> all(t.d.num_cells(), 1);
    const GapModel model(t.d, t.s, t.n, fs, &t.pe);
    ModelFit fit = FitCandidate(model, 0, Scope::kShared, all);
    ASSERT_TRUE(fit.success) << fit.message;
    ASSERT_EQ(fit.terms.size(), 1u);
    EXPECT_FALSE(fit.terms[0].profiled);
    const double fitted = fit.terms[0].values[0][0];
    EXPECT_EQ(fit.terms[0].ci_lo[0][0], fitted);  // the curvature's: the value alone
    EXPECT_EQ(fit.terms[0].ci_hi[0][0], fitted);
    ProfileDiscreteAxes(model, all, &fit);
    const TermFit& tf = fit.terms[0];
    EXPECT_TRUE(tf.profiled);
    EXPECT_EQ(tf.values[0][0], fitted);  // the value stays
    std::printf("%s: width %g [%g, %g], background %.3f [%.3f, %.3f]\n",
                separable ? "separable" : "product", fitted, tf.ci_lo[0][0], tf.ci_hi[0][0],
                tf.values[0][1], tf.ci_lo[0][1], tf.ci_hi[0][1]);
    if (separable) {
      EXPECT_EQ(fitted, 2.0);
      EXPECT_EQ(tf.ci_lo[0][0], 2.0);
      EXPECT_EQ(tf.ci_hi[0][0], 2.0);
      // A fit held at 3 px (as the selection may hold a width chosen beside other terms): the
      // interval is read from the lowest width's refit, so it runs from 2 px (the lowest) to
      // 3 px (the width given, always inside), and 1 px, far above 2 px's deviance though
      // nearer 3 px's, stays out.
      Term at3 = tf.term;
      at3.discrete_node = {{3, -1}};
      ModelFit held = FitTerms(model, {at3}, all);
      ASSERT_TRUE(held.success) << held.message;
      ProfileDiscreteAxes(model, all, &held);
      EXPECT_EQ(held.terms[0].values[0][0], 3.0);
      EXPECT_EQ(held.terms[0].ci_lo[0][0], 2.0);
      EXPECT_EQ(held.terms[0].ci_hi[0][0], 3.0);
    } else {
      EXPECT_EQ(tf.ci_lo[0][0], 1.0);
      EXPECT_EQ(tf.ci_hi[0][0], 5.0);
    }
  }
}

// A discrete width and a window metric in its other mode: under placement scatter the region's
// outline falls on the pixel grid at a phase of its own, and where the far background's share of
// the valid samples is near one half the median jumps to the background (region_spill at 4 px,
// sunset, HA, 12 m: 7.7 to 9.5 m far at 14 of 27 placements within ±4 % at 0°, 10° and 20°,
// docs/gap/cases.md). Here the table is
// 2 px of a spill law on the median under placement scatter (PlacedGrid), and one test point's
// HA recordings read 9 m far; the surface reads that jump at widths of 3 px and more. The fit's
// Huber deviance prefers 3 px (the one test point outweighs the other 31); the width is chosen by
// the biweight, which counts that test point as one miss of bounded weight: 2 px. Per light, the
// sunset's width is chosen on its own cells alike. A table whose law is 3 px keeps 3 px.
TEST(DiscreteWidth, ATestPointInTheOtherModeDoesNotChooseIt) {
  Candidate spill;
  for (const Candidate& c : DefaultCandidates())
    if (c.effect == "region_spill") spill = c;
  ASSERT_EQ(spill.effect, "region_spill");
  auto law = [](double w, double b, double dist) {
    return 0.01 * w * dist * dist + 0.04 * (b - 1) * dist;
  };
  auto jumps = [](const auto& r) {
    return r.light == "sunset" && r.distance_m == 12 && r.angle_deg == 10 && r.preset == "HA";
  };
  for (const double truth : {2.0, 3.0}) {
    SCOPED_TRACE(truth == 2 ? "2 px" : "3 px");
    LimitTable t = MedianTable(
        PlacedGrid(29,
                   [&](const records::PanelMetrics& r) {
                     return law(truth, 2.2, r.distance_m) + (jumps(r) ? 9.0 : 0.0);
                   }),
        spill, [&](const std::vector<double>& v, double dist) { return law(v[0], v[1], dist); });
    Surface& surf = t.s.surfaces[0];
    const int last = static_cast<int>(spill.axes[1].nodes.size());
    const int kk = t.d.num_metrics();
    for (int c = 0; c < t.d.num_cells(); ++c) {
      if (!jumps(t.d.cells[c])) continue;
      for (int node = 0; node < surf.num_nodes; ++node)
        if (spill.axes[0].nodes[node / last] >= 3)
          surf.table[static_cast<size_t>(c) * kk * surf.num_nodes + node] += 9.0;
    }
    const std::vector<char> all(t.d.num_cells(), 1);
    const GapModel model(t.d, t.s, t.n, FitSettings(), &t.pe);
    for (Scope scope : {Scope::kShared, Scope::kPerLight}) {
      ModelFit fit = FitCandidate(model, 0, scope, all);
      ASSERT_TRUE(fit.success) << fit.message;
      ASSERT_EQ(fit.terms.size(), 1u);
      const TermFit& tf = fit.terms[0];
      for (size_t g = 0; g < tf.values.size(); ++g) {
        std::printf("width %g, %s group %zu: %g px, background %.3f\n", truth, ScopeName(scope),
                    g, tf.values[g][0], tf.values[g][1]);
        EXPECT_EQ(tf.values[g][0], truth);
        EXPECT_NEAR(tf.values[g][1], 2.2, 0.2 * 2.2);
      }
    }
    if (truth == 3.0) continue;
    // The fit's own deviance at each width (the node of 2.2 as the background's start).
    double deviance[2];
    for (int w : {2, 3}) {
      Term term{0, Scope::kShared, {{w, -1}}};
      ModelFit start;
      start.terms.emplace_back();
      start.terms[0].term = term;
      start.terms[0].values = {{static_cast<double>(w), 2.2}};
      const ModelFit f = FitTerms(model, {term}, all, &start);
      ASSERT_TRUE(f.success) << f.message;
      deviance[w - 2] = f.Deviance();
    }
    std::printf("Huber deviance at 2 px %.1f, at 3 px %.1f\n", deviance[0], deviance[1]);
    EXPECT_LT(deviance[1], deviance[0]);
  }
}

// A surface added to a MedianTable: `law` of its node's values and the distance on the median.
void AddMedianSurface(LimitTable* t, const Candidate& candidate,
                      const std::function<double(double, double)>& law) {
  Surface surf;
  surf.candidate = candidate;
  surf.num_nodes = static_cast<int>(candidate.axes[0].nodes.size());
  const int kk = t->d.num_metrics();
  for (int c = 0; c < t->d.num_cells(); ++c)
    for (int k = 0; k < kk; ++k)
      for (int node = 0; node < surf.num_nodes; ++node)
        surf.table.push_back(t->s.base[static_cast<size_t>(c) * kk + k] +
                             (k == 0 ? law(candidate.axes[0].nodes[node],
                                           t->d.cells[c].distance_m)
                                     : 0));
  t->s.surfaces.push_back(surf);
}

// Two kept effects that each stand in for the other beside an effect along the calibration are
// not both named with it (AlongCalibration). The median departs by an offset's law (−0.5 px,
// read far ∝ D²) and a scale's (6 %, ∝ D), under placement scatter; a third candidate, along the
// calibration, moves the median by rate × (the offset's law at −1 px − 25 % of D). Beside it,
// either kept effect gives the other's part (at a rate of 0.5 or −0.24), so each no longer earns
// beside it and the other; it alone cannot give both. Judged together (the rule as it was, checked
// by hand), both were dropped and the gap left to nothing; one at a time, one is named "one of"
// with it and the other stays.
TEST(AlongCalibration, TwoKeptEffectsThatStandInForEachOtherAreNotBothDropped) {
  Candidate offset, scale, drift;
  for (const Candidate& c : DefaultCandidates()) {
    if (c.effect == "disparity_offset") offset = c;
    if (c.effect == "depth_scale") scale = c;
    if (c.effect == "temporal_drift") drift = c;
  }
  for (Candidate* c : {&offset, &scale, &drift}) c->range_law = false;  // the laws as given
  auto truth = [](const records::PanelMetrics& r) {
    return OffsetLaw(-0.5, r.distance_m) + 0.06 * r.distance_m;
  };
  LimitTable t = MedianTable(PlacedGrid(43, truth), offset,
                             [](const std::vector<double>& v, double d) {
                               return OffsetLaw(v[0], d);
                             });
  AddMedianSurface(&t, scale, [](double v, double d) { return v * d; });
  AddMedianSurface(&t, drift,
                   [](double v, double d) { return v * (OffsetLaw(-1, d) - 0.25 * d); });
  const std::vector<char> all(t.d.num_cells(), 1);
  GapModel model(t.d, t.s, t.n, FitSettings(), &t.pe);
  model.SetAbsorbs(2, 1);  // the drift along σ_d
  const ModelFit m0 = FitTerms(model, {}, all);
  ASSERT_TRUE(m0.success) << m0.message;
  Selection r;
  for (int i = 0; i < 3; ++i) {
    const ModelFit alone = FitCandidate(model, i, Scope::kShared, all);
    ASSERT_TRUE(alone.success) << alone.message;
    EffectResult e;
    e.name = t.s.surfaces[i].candidate.effect;
    e.fit = alone.terms[0];
    e.earns = true;
    r.effects.push_back(e);
  }
  const std::vector<Term> kept{r.effects[0].fit.term, r.effects[1].fit.term};
  ModelFit start = m0;
  start.terms = {r.effects[0].fit, r.effects[1].fit};
  const ModelFit current = FitTerms(model, kept, all, &start);
  ASSERT_TRUE(current.success) << current.message;
  std::printf("kept together: offset %.3f px, scale %.4f\n", current.terms[0].values[0][0],
              current.terms[1].values[0][0]);
  // The premise: beside the drift either kept effect fits as the two do; the drift alone cannot.
  auto deviance = [&](const std::vector<int>& set) {
    std::vector<Term> terms;
    ModelFit from = m0;
    for (int i : set) {
      terms.push_back(r.effects[i].fit.term);
      from.terms.push_back(r.effects[i].fit);
    }
    const ModelFit f = FitTerms(model, terms, all, &from);
    EXPECT_TRUE(f.success) << f.message;
    return f.Deviance();
  };
  const double both = current.Deviance();
  std::printf("deviance: both %.1f, offset + drift %.1f, scale + drift %.1f, drift %.1f\n", both,
              deviance({0, 2}), deviance({1, 2}), deviance({2}));
  EXPECT_LT(deviance({0, 2}), both + 10);
  EXPECT_LT(deviance({1, 2}), both + 10);
  EXPECT_GT(deviance({2}), both + 100);
  r.steps = {{"disparity_offset"}, {"depth_scale"}};
  r.chosen = {0, 1};
  const std::vector<char> keep = AlongCalibration(model, m0, current, all, &r);
  ASSERT_EQ(keep.size(), 2u);
  for (const std::string& d : r.dropped) std::printf("dropped: %s\n", d.c_str());
  EXPECT_EQ(keep[0] + keep[1], 1);
  ASSERT_EQ(r.ambiguous.size(), 1u);
  EXPECT_EQ(r.ambiguous[0].effects.back(), "temporal_drift");
}

// A range law the spreads contradict is not kept (MedianWithoutSpreads). SpreadTable's rows: a
// placement moves the median and the spread together, as the camera's do, and the base placed
// 2 % further tells the model so. The median departs by an offset of −0.2 px (0.86 m far at
// 16 m) in both tables: in one the spreads widen with it (the offset itself: kept, at its size),
// in the other they do not (a median over-read the registry does not hold: not kept, the reason
// given). A rule reading the median alone keeps both; one reading the spreads without their
// noise and the calibration drops both. Over draws 1–30 of these tables the test passes at 29
// (at 11 the over-read is kept), and with the rule reading each metric's scatter as its own
// (FitSettings::joint_placement off) at 12.
// PlacedGrid's design at seed `seed` (each test point placed off by τ(D) = 0.05 m + 2 % of D),
// each recording's median read through a disparity offset of `delta_px` and its plane_std
// 0.002 m·(Z/1 m)² with 1 % of replicate noise, Z its placed depth, read through the offset
// too where `spreads_follow`; `moved` (by `move_m` at test point `moved_point`, the spreads as
// `spreads_follow` says) on top. Against a base at the nominal distance, an offset's surface
// (median to Z' = f·B / (f·B / Z + δ), log plane_std by 2·ln(Z'/Z)), and the base placed 2 %
// further (Simulations::moved).
LimitTable SpreadTable(std::uint32_t seed, double delta_px, bool spreads_follow,
                       int moved_point = -1, double move_m = 0) {
  constexpr double kFb = 60.8;
  auto far = [&](double delta, double z) { return kFb / (kFb / z + delta); };
  Candidate offset;
  for (const Candidate& c : DefaultCandidates())
    if (c.effect == "disparity_offset") offset = c;
  offset.range_law = true;
  offset.moves_window = false;
  std::mt19937 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::map<std::string, double> shift;
  std::map<std::string, int> point;
  std::vector<records::PanelMetrics> rows = ArticleGrid();
  for (auto& r : rows) {
    const std::string key = r.light + std::to_string(r.distance_m) + std::to_string(r.angle_deg);
    if (!shift.count(key)) {
      shift[key] = (0.05 + 0.02 * r.distance_m) * unit(rng);
      point[key] = static_cast<int>(point.size());
    }
    const double z = r.distance_m + shift[key];
    const double moved = point[key] == moved_point ? move_m : 0.0;
    r.median_m = far(delta_px, z) + moved + 0.005 * unit(rng);
    r.mean_m = r.median_m + 0.01;
    const double spread_z = (spreads_follow ? far(delta_px, z) + moved : z);
    r.plane_std_m = 0.002 * spread_z * spread_z * std::exp(0.01 * unit(rng));
  }
  LimitTable t;
  std::string why;
  if (!BuildDesign(rows, &t.d, &why)) throw std::runtime_error(why);
  const int kk = t.d.num_metrics();
  const int kstd = static_cast<int>(
      std::find(t.d.metrics.begin(), t.d.metrics.end(), kPlaneStd) - t.d.metrics.begin());
  if (kstd >= kk) throw std::runtime_error("no plane_std compared");
  t.s.metrics = t.d.metrics;
  t.s.base.assign(t.d.real.size(), 0.0);
  t.s.jac_log_sigma.assign(t.d.real.size(), 0.0);
  t.s.jac_logit_p.assign(t.d.real.size(), 0.0);
  Surface surf;
  surf.candidate = offset;
  surf.num_nodes = static_cast<int>(offset.axes[0].nodes.size());
  for (int c = 0; c < t.d.num_cells(); ++c) {
    const double dist = t.d.cells[c].distance_m;
    t.s.depth_m.push_back(dist);
    for (int k = 0; k < kk; ++k) {
      const size_t o = static_cast<size_t>(c) * kk + k;
      if (k == kstd) {
        t.s.base[o] = std::log(0.002 * dist * dist);
        t.s.jac_log_sigma[o] = 1;  // a spread is ∝ σ_d
      } else if (k > 0) {
        t.s.base[o] = t.d.real[o];
      }
      for (double delta : offset.axes[0].nodes) {
        double v = t.s.base[o];
        if (k == 0) v += far(delta, dist) - dist;
        if (k == kstd) v += 2 * std::log(far(delta, dist) / dist);
        surf.table.push_back(v);
      }
    }
  }
  t.s.surfaces.push_back(surf);
  t.s.moved_rel = 0.02;
  t.s.moved = t.s.base;
  for (int c = 0; c < t.d.num_cells(); ++c) {
    t.s.moved[static_cast<size_t>(c) * kk] += 0.02 * t.d.cells[c].distance_m;
    t.s.moved[static_cast<size_t>(c) * kk + kstd] += 2 * std::log(1.02);
  }
  t.n = EstimateNoise(t.d, t.s);
  t.pe = EstimatePlacement(t.d, t.s, t.n, std::vector<char>(t.d.num_cells(), 1), 0.05);
  return t;
}

TEST(MedianWithoutSpreads, ARangeLawIsKeptOnlyWhereTheSpreadsFollowIt) {
  for (const bool spreads_follow : {true, false}) {
    const LimitTable t = SpreadTable(97, -0.2, spreads_follow);
    const int kk = t.d.num_metrics();
    const std::vector<char> all(t.d.num_cells(), 1);
    std::vector<int> fold(t.d.num_cells());
    for (int c = 0; c < t.d.num_cells(); ++c)
      fold[c] = static_cast<int>(t.d.cells[c].distance_m / 4) - 1;
    GapModel model(t.d, t.s, t.n, FitSettings(), &t.pe);
    model.SetDispersion(std::vector<double>(kk, 1.0));
    const ModelFit m0 = FitTerms(model, {}, all);
    ASSERT_TRUE(m0.success) << m0.message;
    ModelFit current = FitCandidate(model, 0, Scope::kShared, all);
    ASSERT_TRUE(current.success) << current.message;
    HeldOut current_ho = CrossValidate(model, {current.terms[0].term}, fold, 4, current, all);
    Selection r;
    r.steps = {{"disparity_offset"}};
    r.chosen = {0};
    std::printf("spreads %s: offset fitted %.3f px, deviance %.1f\n",
                spreads_follow ? "follow" : "stay", current.terms[0].values[0][0],
                current.Deviance());
    if (spreads_follow) {
      EXPECT_NEAR(current.terms[0].values[0][0], -0.2, 0.05);
    }
    ASSERT_TRUE(MedianWithoutSpreads(model, m0, all, fold, 4, &current, &current_ho, &r));
    for (const std::string& d : r.dropped) std::printf("dropped: %s\n", d.c_str());
    EXPECT_EQ(r.steps.size(), spreads_follow ? 1u : 0u);
    EXPECT_EQ(r.dropped.size(), spreads_follow ? 0u : 1u);
    // What the spreads say of the law kept (gap.json's selected[].spreads): they confirm it.
    ASSERT_EQ(r.spreads.size(), spreads_follow ? 1u : 0u);
    if (spreads_follow) {
      const SpreadsEvidence& e = r.spreads[0];
      std::printf("spreads: deviance %.1f with them, %.1f with the median's law alone\n", e.with,
                  e.median_only);
      EXPECT_EQ(e.candidate, 0);
      EXPECT_TRUE(e.Confirms());
      EXPECT_NE(SpreadsEvidenceText(r.spreads, 0, "disparity_offset").find("confirm it"),
                std::string::npos);
      EXPECT_EQ(SpreadsEvidenceText(r.spreads, 1, "depth_scale"), "");
    }
  }
}

// The two fits have the same parameters, so their deviance difference f is twice the log of
// their likelihood ratio: odds of e^(f/2) for the law against the median's law alone.
TEST(MedianWithoutSpreads, TheSpreadsEvidenceIsReadAsOdds) {
  const std::vector<SpreadsEvidence> e = {{2, 100, 105.2}, {3, 100, 97}, {4, 100, 130}};
  auto text = [&](int c) { return SpreadsEvidenceText(e, c, "law"); };
  EXPECT_NE(text(2).find("cannot tell it from a median over-read outside the registry (deviance "
                         "5.2 lower with its departures in them than with the median's law "
                         "alone, odds of 13 to 1 for it"),
            std::string::npos)
      << text(2);
  EXPECT_NE(text(3).find("deviance -3 lower"), std::string::npos) << text(3);
  EXPECT_NE(text(3).find("odds of 1 to 4.5 for it"), std::string::npos) << text(3);
  EXPECT_NE(text(4).find("the spreads confirm it"), std::string::npos) << text(4);
  EXPECT_NE(text(4).find("odds of over 1000 to 1"), std::string::npos) << text(4);
  EXPECT_EQ(text(5), "");
}

// One displacement is read once (fit.h, (2): FitSettings::joint_placement). SpreadTable's rows
// without offset, one test point at 16 m moved 1.2 m further (three times its placement law)
// in its median, its plane_std moving with it or not. Against the base, a panel that stood
// further is a median and a spread that depart together: with the displacement shared it costs
// less than a median that departs alone, whose spread then contradicts it. With each metric's
// scatter its own, the spread's departure is counted as a second, independent miss, and the
// panel that stood further costs more (built to fail there).
TEST(Placement, OneDisplacementIsReadOnceInTheMedianAndTheSpread) {
  int point16 = -1;
  {
    const LimitTable t = SpreadTable(41, 0, true);
    for (int c = 0; c < t.d.num_cells() && point16 < 0; ++c)
      if (t.d.cells[c].distance_m == 16) point16 = t.pe.point[c];
  }
  ASSERT_GE(point16, 0);
  double cost[2][2];  // [joint][spreads follow]
  for (const bool follow : {false, true}) {
    const LimitTable t = SpreadTable(41, 0, follow, point16, 1.2);
    const std::vector<char> all(t.d.num_cells(), 1);
    for (const bool joint : {false, true}) {
      FitSettings fs;
      fs.joint_placement = joint;
      fs.huber_k = 0;
      GapModel model(t.d, t.s, t.n, fs, &t.pe);
      model.SetDispersion(std::vector<double>(t.d.num_metrics(), 1.0));
      std::map<long long, double> per_unit;
      model.DataDeviance(t.s.base, all, &per_unit);
      cost[joint][follow] = per_unit[point16];
    }
  }
  std::printf("the moved test point's deviance: shared %.1f (spread follows), %.1f (stays); "
              "each its own %.1f, %.1f\n",
              cost[1][1], cost[1][0], cost[0][1], cost[0][0]);
  EXPECT_LT(cost[1][1], cost[1][0]);
  EXPECT_GT(cost[0][1], cost[0][0]);
}

// The two dispersions (Dispersion; fit.h, (2)). PlacedGrid's rows (τ(D) = 0.05 m + 2 % of D,
// 5 mm between emitter twins), each preset of a test point read off by its own draw of 2 cm (a
// departure the twins share, as a preset the simulator does not reproduce is): the recordings
// spread about their test point's mean several times the twins' variance, while the test
// points' means spread as the placement law says. About a prediction that holds the table's law
// (an offset of −0.3 px: 1.26 m far at 16 m), φ reads that spread (7.2) and ψ about 1; about the
// base, which lacks the law, ψ takes it and φ does not move. One dispersion for both components
// (the rule before: every residual over √(σ² + τ²), one robust scale) reads about 1 here: the
// recordings' spread is lost under the placement law, and the fits weighed it as replicate
// noise. Where that one scale is wider than 1 (the median's 5.4 on the article's rows with an
// offset of −0.97 px injected), it widened the placement law by as much, and an effect acting on
// the test points' means lost that share of its evidence.
TEST(Dispersion, TheRecordingsOfATestPointAndTheTestPointsMeansEachHaveTheirOwn) {
  std::mt19937 rng(71);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::map<std::string, double> preset_shift;
  auto truth = [&](const records::PanelMetrics& r) {
    const std::string key =
        r.light + r.preset + std::to_string(r.distance_m) + std::to_string(r.angle_deg);
    if (!preset_shift.count(key)) preset_shift[key] = 0.02 * unit(rng);
    return OffsetLaw(-0.3, r.distance_m) + preset_shift[key];
  };
  Candidate offset = DefaultCandidates()[0];
  offset.range_law = false;
  const LimitTable t = MedianTable(PlacedGrid(17, truth), offset,
                                   [](const std::vector<double>& v, double d) {
                                     return OffsetLaw(v[0], d);
                                   });
  const std::vector<char> all(t.d.num_cells(), 1);
  GapModel model(t.d, t.s, t.n, FitSettings(), &t.pe);
  const int kk = model.num_metrics();
  ModelFit law;
  TermFit term;
  term.term.candidate = 0;
  term.values = {{-0.3}};
  law.terms = {term};
  const std::vector<double> at_law = Dispersion(model, model.Predict(law), all);
  const std::vector<double> at_base = Dispersion(model, t.s.base, all);
  ASSERT_EQ(at_law.size(), 2u * kk);
  std::printf("median: about the law phi %.2f psi %.2f; about the base phi %.2f psi %.2f\n",
              at_law[0], at_law[kk], at_base[0], at_base[kk]);
  EXPECT_GT(at_law[0], 6.0);
  EXPECT_LT(at_law[kk], 1.8);
  EXPECT_GT(at_base[kk], 5.0);
  EXPECT_NEAR(at_base[0], at_law[0], 0.05 * at_law[0]);
  // The one scale of every residual over √(σ² + τ²) about the law, as it was read.
  std::vector<double> z;
  for (size_t o = 0; o < static_cast<size_t>(model.num_obs()); o += kk)
    if (model.valid(o)) z.push_back((model.y(o) - model.Predict(law)[o]) / model.noise(o));
  double mean_sq = 0;
  for (double v : z) mean_sq += v * v / static_cast<double>(z.size());
  std::printf("one scale: mean z^2 %.2f\n", mean_sq);
  EXPECT_LT(mean_sq, 0.25 * at_law[0]);
}

// The keep rule's share (MovedShare): two metrics, three observations each (observation o is
// metric o % 2). The change moves metric 0 only: its share is that metric's, whatever gap
// metric 1 holds (read as a share of the whole, a gap of 100 there would take it from 0.75 to
// under 0.1). Moving both, each metric weighs by the change's Σ(without − with)² in it.
TEST(KeepRule, TheShareIsReadInTheMetricsTheChangeMoves) {
  const std::vector<double> without = {2, 5, 2, 5, 2, 5}, with = {1, 5, 1, 5, 1, 5};
  // Metric 0: gain 3 × (4 − 1) = 9 of a gap of 12; metric 1: nothing moves.
  EXPECT_NEAR(MovedShare(without, with, without, 2), 0.75, 1e-12);
  std::vector<double> wider = without;
  for (size_t o = 1; o < wider.size(); o += 2) wider[o] = 100;
  EXPECT_NEAR(MovedShare(without, with, wider, 2), 0.75, 1e-12);
  // Both moved: metric 1 from 5 to 4 (movement 3, gain 27 of 75); metric 0 as above
  // (movement 3, gain 9 of 12): (3·9 + 3·27) / (3·12 + 3·75).
  const std::vector<double> both = {1, 4, 1, 4, 1, 4};
  EXPECT_NEAR(MovedShare(without, both, without, 2), (27.0 + 81) / (36 + 225), 1e-12);
  // Non-finite observations are left out; nothing moved gives NaN.
  std::vector<double> holes = with;
  holes[0] = NAN;
  EXPECT_NEAR(MovedShare(without, holes, without, 2), 6.0 / 8, 1e-12);
  EXPECT_TRUE(std::isnan(MovedShare(without, without, without, 2)));
}

TEST(Limits, AtTheLimitTheFitGainsTheNoncentralityAskedAndTheGainTheShareAsks) {
  const LimitTable t = MakeLimitTable(31);
  FitSettings fs;
  fs.huber_k = 0;  // plain squares: the deviance is the noncentrality
  const std::vector<char> all(t.d.num_cells(), 1);
  const GapModel model(t.d, t.s, t.n, fs, &t.pe);
  const DetectionLimits lim = FindDetectionLimits(model, all);
  ASSERT_EQ(lim.effects.size(), 1u);
  const DetectionLimit& e = lim.effects[0];
  EXPECT_NEAR(lim.z_needed, std::sqrt(std::log(lim.observations)) + 0.8416, 1e-3);
  EXPECT_EQ(lim.far_distance_m, 16);
  ASSERT_TRUE(std::isfinite(e.size[0]) && std::isfinite(e.size[1]));
  EXPECT_LT(e.size[0], 0);
  EXPECT_GT(e.size[1], 0);
  EXPECT_NEAR(e.size[0], -e.size[1], 1e-3 * e.size[1]);  // a law linear in δ
  EXPECT_NEAR(e.far_m[1], OffsetLaw(e.size[1], 16), 1e-6);
  EXPECT_EQ(e.by_test[1], e.size[1]);  // no gap given: the test alone
  EXPECT_TRUE(std::isnan(e.by_share[1]));
  std::printf("limit: delta_px ±%.4f (%.3f m at 16 m)\n", e.size[1], e.far_m[1]);

  for (int side = 0; side < 2; ++side) {
    Design at = t.d;  // the base plus the departure at the limit, noise-free
    const int kk = at.num_metrics();
    for (int c = 0; c < at.num_cells(); ++c)
      at.real[static_cast<size_t>(c) * kk] = OffsetLaw(e.size[side], at.cells[c].distance_m);
    const GapModel exact(at, t.s, t.n, fs, &t.pe);
    const ModelFit m0 = FitTerms(exact, {}, all);
    const ModelFit f = FitCandidate(exact, 0, Scope::kShared, all);
    ASSERT_TRUE(m0.success && f.success);
    const double drop = m0.Deviance() - f.Deviance();
    EXPECT_NEAR(drop, lim.z_needed * lim.z_needed, 0.02 * lim.z_needed * lim.z_needed);
    EXPECT_NEAR(f.terms[0].values[0][0], e.size[side], 0.02 * std::fabs(e.size[side]));
    EXPECT_GT(m0.Deviance(), 1.0) << "the calibration cannot take the whole law";
  }

  // The share of the gap, with the table held out by distance (four folds): where the law's
  // Σz² gain γ_f over each fold's observations, against the fold's calibrated Σz² G_f,
  // averages γ_f / (G_f + γ_f) = p over the folds (its own part); pooled, Σγ_f / Σ(G_f + γ_f)
  // = p too, the higher bar deciding. Read in the whole gap and in the metric the law moves,
  // the lower size of the two.
  const int kk = t.d.num_metrics();
  std::vector<int> fold(t.d.num_cells());
  for (int c = 0; c < t.d.num_cells(); ++c)
    fold[c] = static_cast<int>(t.d.cells[c].distance_m / 4) - 1;
  auto gains = [&](double delta) {
    std::vector<double> g(4, 0.0);
    for (int o = 0; o < model.num_obs(); ++o)
      if (model.valid(o) && o % kk == 0)
        g[fold[o / kk]] += std::pow(OffsetLaw(delta, t.d.cells[o / kk].distance_m) /
                                        model.noise(o), 2);
    return g;
  };
  // The last: a 16 m fold with almost no gap of its own, where the law's own part is won at
  // once and the pooled share decides.
  const std::vector<std::vector<double>> fold_gaps = {
      {50, 100, 50, 150}, {500, 1000, 500, 1500}, {1250, 1250, 1250, 0.25}};
  // Each fold also holds three times that gap in metric 1, which the law leaves alone: the whole
  // reading's G_f is 4 times the moved reading's. A floor of 0.99 turns a reading off.
  for (const std::vector<double>& gaps : fold_gaps) {
    const double scale = gaps[0];
    ASSERT_GE(kk, 2);
    LimitSettings ls;
    ls.fold = fold;
    for (double g : gaps) {
      ls.fold_gap_sq.emplace_back(kk, 0.0);
      ls.fold_gap_sq.back()[0] = g;
      ls.fold_gap_sq.back()[1] = 3 * g;
    }
    ls.pooled = false;
    LimitSettings whole_only = ls, moved_only = ls;
    whole_only.min_moved_share = whole_only.min_own_moved_share = 0.99;
    moved_only.min_share = moved_only.min_own_share = 0.99;
    // The mean over the folds of γ_f / (G_f + γ_f) at a size, G_f read in metric 0 alone
    // (times 1) or in the whole (times 4).
    auto mean_share = [&](double delta, double times) {
      const std::vector<double> g = gains(delta);
      double mean = 0;
      for (int f = 0; f < 4; ++f) mean += g[f] / (times * gaps[f] + g[f]) / 4;
      return mean;
    };
    const DetectionLimit by_whole = FindDetectionLimits(model, all, whole_only).effects[0];
    const DetectionLimit by_moved = FindDetectionLimits(model, all, moved_only).effects[0];
    const DetectionLimit own = FindDetectionLimits(model, all, ls).effects[0];
    ASSERT_TRUE(std::isfinite(by_whole.by_share[1]) && std::isfinite(by_moved.by_share[1]))
        << scale;
    EXPECT_NEAR(mean_share(by_whole.by_share[1], 4), ls.min_own_share, 2e-3) << scale;
    EXPECT_NEAR(mean_share(by_moved.by_share[1], 1), ls.min_own_moved_share, 2e-3) << scale;
    EXPECT_NEAR(own.by_share[1], std::min(by_whole.by_share[1], by_moved.by_share[1]), 1e-9)
        << "either reading keeps it";
    EXPECT_NEAR(own.by_test[1], e.size[1], 1e-9);
    EXPECT_EQ(own.size[1], std::max(own.by_test[1], own.by_share[1])) << scale;
    // The gap in metric 1 raises the whole reading's bar only.
    LimitSettings here = moved_only;
    for (auto& f : here.fold_gap_sq) f[1] = 0;
    EXPECT_NEAR(FindDetectionLimits(model, all, here).effects[0].by_share[1],
                by_moved.by_share[1], 1e-9);

    // Pooled too (the whole reading): Σγ_f / Σ(G_f + γ_f) reaches the selection's floor where
    // it is the higher bar.
    whole_only.pooled = true;
    const DetectionLimit both = FindDetectionLimits(model, all, whole_only).effects[0];
    const std::vector<double> g = gains(both.by_share[1]);
    double gain = 0, whole = 0;
    for (int f = 0; f < 4; ++f) {
      gain += g[f];
      whole += 4 * gaps[f] + g[f];
    }
    EXPECT_GE(both.by_share[1], by_whole.by_share[1] - 1e-9);
    if (gaps[3] < 10) {
      EXPECT_GT(both.by_share[1], 2 * by_whole.by_share[1]) << "the pooled share";
    }
    EXPECT_NEAR(std::min(mean_share(both.by_share[1], 4), gain / whole), ls.min_share, 2e-3)
        << scale;
    std::printf("fold gaps from %g: by the whole's share %.4f px (pooled too %.4f px), "
                "by the moved metrics' %.4f px\n",
                scale, by_whole.by_share[1], both.by_share[1], by_moved.by_share[1]);
  }

  // Without placement scatter every recording is its own piece of evidence: a smaller limit.
  const GapModel no_placement(t.d, t.s, t.n, fs, nullptr);
  const double bare = FindDetectionLimits(no_placement, all).effects[0].size[1];
  EXPECT_LT(bare, 0.5 * e.size[1]);
  // A calibration direction that could mimic the law takes part of its evidence.
  Simulations held = t.s;
  std::fill(held.jac_log_sigma.begin(), held.jac_log_sigma.end(), 0.0);
  const GapModel frozen(t.d, held, t.n, fs, &t.pe);
  EXPECT_LT(FindDetectionLimits(frozen, all).effects[0].size[1], e.size[1]);
}

// Beside a selection, a limit is what the effect adds past what the selected terms can take:
// on the placed grid (seed 23, not the other tests' draws) with a disparity offset kept, a depth
// scale (∝ D, the offset ∝ D²) is seen from a larger size than alone. Checked against the fit
// itself: on a noise-free table reading the base, the kept offset and the scale at that limit,
// the fit of both gains (√(ln n) + Φ⁻¹(0.8))² over the offset's alone within 3 %, and reads the
// scale there; at the limit read alone it gains less than half of that. The same with the
// offset kept per light, each light's direction on its own cells. The effect's own term in the selection is not set beside it: its limit is
// its limit alone. And a kept law whose direction depends on its value, −(v + v²)·D²/60.8 −
// 0.1·v²·D, is read where it was fitted: its limit beside v = −0.2 is not the one beside v = 0.
TEST(Limits, BesideASelectionTheLimitIsWhatTheSelectionCannotTake) {
  Candidate offset = DefaultCandidates()[0], scale;
  for (const Candidate& c : DefaultCandidates())
    if (c.effect == "depth_scale") scale = c;
  ASSERT_EQ(scale.effect, "depth_scale");
  offset.range_law = scale.range_law = false;
  auto scale_law = [](double s, double dist) { return s * dist; };
  const std::vector<records::PanelMetrics> rows = PlacedGrid(23, nullptr);
  // The grid against the kept law's surface and the scale's.
  auto make = [&](const std::function<double(double, double)>& kept_law) {
    LimitTable t = MedianTable(rows, offset, [&](const std::vector<double>& v, double dist) {
      return kept_law(v[0], dist);
    });
    t.s.surfaces.push_back(MedianTable(rows, scale, [&](const std::vector<double>& v,
                                                        double dist) {
                             return scale_law(v[0], dist);
                           }).s.surfaces.at(0));
    return t;
  };
  FitSettings fs;
  fs.huber_k = 0;
  const LimitTable t = make(OffsetLaw);
  const std::vector<char> all(t.d.num_cells(), 1);
  const GapModel model(t.d, t.s, t.n, fs, &t.pe);
  const DetectionLimits alone = FindDetectionLimits(model, all);
  ASSERT_EQ(alone.effects.size(), 2u);
  const double s_alone = alone.effects[1].size[1];
  const int kk = t.d.num_metrics();
  double beside_shared = NAN;
  for (const Scope scope : {Scope::kShared, Scope::kPerLight}) {
    SCOPED_TRACE(ScopeName(scope));
    const Term kept_term{0, scope, {{-1}}};
    ModelFit selection = FitTerms(model, {kept_term}, all);
    ASSERT_TRUE(selection.success) << selection.message;
    const std::vector<double> by_light =
        scope == Scope::kShared ? std::vector<double>{-0.2} : std::vector<double>{-0.2, -0.1};
    ASSERT_EQ(selection.terms[0].values.size(), by_light.size());
    for (size_t g = 0; g < by_light.size(); ++g) selection.terms[0].values[g][0] = by_light[g];
    const DetectionLimits beside = FindDetectionLimits(model, all, {}, &selection);
    ASSERT_EQ(beside.effects.size(), 2u);
    const double s_beside = beside.effects[1].size[1];
    ASSERT_TRUE(std::isfinite(s_alone) && std::isfinite(s_beside));
    std::printf("%s: depth_scale limit alone %+.4f, beside the offset %+.4f\n", ScopeName(scope),
                s_alone, s_beside);
    EXPECT_GT(s_beside, 1.5 * s_alone) << "D and D² alike over 4 to 16 m";
    EXPECT_EQ(beside.effects[0].size[1], alone.effects[0].size[1]);
    // Both lights on one grid: each light's offset direction takes that light's part of the
    // scale as the shared one takes the whole.
    if (scope == Scope::kShared)
      beside_shared = s_beside;
    else
      EXPECT_NEAR(s_beside, beside_shared, 0.01 * beside_shared);

    for (const double s : {s_beside, s_alone}) {
      Design at = t.d;  // the base, the kept offset (each light's) and the scale s
      for (int c = 0; c < at.num_cells(); ++c) {
        const double dist = at.cells[c].distance_m;
        const double v = by_light[by_light.size() == 1 ? 0 : at.scenario_light[at.scenario[c]]];
        at.real[static_cast<size_t>(c) * kk] =
            t.s.base[static_cast<size_t>(c) * kk] + OffsetLaw(v, dist) + scale_law(s, dist);
      }
      const GapModel exact(at, t.s, t.n, fs, &t.pe);
      const ModelFit kept_only = FitTerms(exact, {kept_term}, all, &selection);
      const ModelFit both =
          FitTerms(exact, {kept_term, Term{1, Scope::kShared, {{-1}}}}, all, &selection);
      ASSERT_TRUE(kept_only.success && both.success);
      const double drop = kept_only.Deviance() - both.Deviance();
      const double z2 = beside.z_needed * beside.z_needed;
      if (s == s_alone) {
        EXPECT_LT(drop, 0.5 * z2) << "alone, the limit would promise what the fit barely sees";
        continue;
      }
      EXPECT_NEAR(drop, z2, 0.03 * z2);
      EXPECT_NEAR(both.terms[1].values[0][0], s_beside, 0.03 * s_beside);
      for (size_t g = 0; g < by_light.size(); ++g)
        EXPECT_NEAR(both.terms[0].values[g][0], by_light[g], 0.03 * std::fabs(by_light[g]));
    }
  }

  // The bent law: its direction at −0.2 is −0.6·D²/60.8 + 0.04·D, at 0 −D²/60.8.
  const LimitTable b = make([](double v, double dist) {
    return -(v + v * v) * dist * dist / 60.8 - 0.1 * v * v * dist;
  });
  const GapModel bent(b.d, b.s, b.n, fs, &b.pe);
  ModelFit at_v = FitTerms(bent, {Term{0, Scope::kShared, {{-1}}}}, all);
  ASSERT_TRUE(at_v.success) << at_v.message;
  double limit_at[2];
  for (int i = 0; i < 2; ++i) {
    at_v.terms[0].values[0][0] = i == 0 ? -0.2 : 0.0;
    limit_at[i] = FindDetectionLimits(bent, all, {}, &at_v).effects[1].size[1];
  }
  std::printf("bent law: depth_scale limit beside v = -0.2 %+.4f, beside v = 0 %+.4f\n",
              limit_at[0], limit_at[1]);
  ASSERT_TRUE(std::isfinite(limit_at[0]) && std::isfinite(limit_at[1]));
  EXPECT_GT(std::fabs(limit_at[0] - limit_at[1]), 0.05 * limit_at[1]);
}

TEST(ChiSquare, SurvivalMatchesKnownQuantiles) {
  EXPECT_NEAR(ChiSquareSurvival(3.841459, 1), 0.05, 1e-6);
  EXPECT_NEAR(ChiSquareSurvival(9.487729, 4), 0.05, 1e-6);
  EXPECT_NEAR(ChiSquareSurvival(23.20925, 10), 0.01, 1e-6);
  EXPECT_NEAR(ChiSquareSurvival(0, 3), 1.0, 1e-12);
}

// The shrink is the share of the gap beyond the noise: a model matching the camera leaves mean
// z² = 1 and reaches 100 %, however much of the table sat at its noise floor.
TEST(Shrink, IsTheShareOfTheGapBeyondTheNoise) {
  auto stat = [](double overall) {
    GapStat g;
    g.overall = overall;
    g.count = 224;
    return g;
  };
  // Six metrics at the floor (z² 1) and one at 20: mean 23 / 7 before, 1 after.
  const double before = (6 + 20) / 7.0;
  EXPECT_NEAR(Shrink(stat(before), stat(1.0)), 100.0, 1e-9);
  EXPECT_LT(100 * (1 - 1.0 / before), 73.1);  // the plain ratio could not get there
  EXPECT_NEAR(Shrink(stat(5.0), stat(3.0)), 50.0, 1e-9);
  EXPECT_NEAR(Shrink(stat(5.0), stat(7.0)), -50.0, 1e-9);  // a model that widens the gap
  EXPECT_TRUE(std::isnan(Shrink(stat(1.0), stat(0.8))));  // no gap to shrink
  EXPECT_TRUE(std::isnan(Shrink(stat(0.9), stat(0.8))));
}

// A surface row along a parameter: the smooth keeps a response larger than the nodes' scatter
// (the median along an offset, curved towards its pole), takes the trend through draws of the
// scatter's size (a width jumping by whole pixels), and never moves the neutral node.
TEST(Smooth, KeepsAResponseAndTakesTheTrendThroughDraws) {
  const std::vector<double> x = {-1, -0.5, -0.25, -0.1, -0.04, 0, 0.04, 0.1, 0.25, 0.5, 1};
  const int n = static_cast<int>(x.size());
  const int neutral = 5;
  // The median's response at 16 m: Z' − Z with Z' = Z / (1 + δ·Z / fB), fB = 58 px·m.
  auto response = [](double d) { return 16.0 / (1 + d * 16.0 / 58.0) - 16.0; };
  std::vector<double> y(n);
  for (int j = 0; j < n; ++j) y[j] = response(x[j]);
  std::vector<double> kept = y;
  SmoothAlong(x.data(), kept.data(), n, neutral, 0.01);
  for (int j = 0; j < n; ++j) EXPECT_NEAR(kept[j], y[j], 0.05) << "node " << x[j];
  EXPECT_EQ(kept[neutral], y[neutral]);

  // A trend of 2 % per px with draws of σ = 0.01 about it (seed 9101): over 200 rows the smooth
  // is nearer the trend than the nodes, and the neutral node stays.
  std::mt19937 rng(9101);
  std::normal_distribution<double> noise(0.0, 0.01);
  double raw_sq = 0, smooth_sq = 0;
  for (int row = 0; row < 200; ++row) {
    std::vector<double> v(n), truth(n);
    for (int j = 0; j < n; ++j) {
      truth[j] = 1.0 - 0.02 * x[j];
      v[j] = truth[j] + (j == neutral ? 0.0 : noise(rng));
    }
    const double at_neutral = v[neutral];
    for (int j = 0; j < n; ++j) raw_sq += (v[j] - truth[j]) * (v[j] - truth[j]);
    SmoothAlong(x.data(), v.data(), n, neutral, 0.01);
    EXPECT_EQ(v[neutral], at_neutral);
    for (int j = 0; j < n; ++j) smooth_sq += (v[j] - truth[j]) * (v[j] - truth[j]);
  }
  EXPECT_LT(smooth_sq, 0.5 * raw_sq);
  // Told there is no scatter, the nodes stay as they are.
  std::vector<double> v = {1, 2, 1, 2, 1, 2, 1, 2, 1, 2, 1};
  const std::vector<double> before = v;
  SmoothAlong(x.data(), v.data(), n, neutral, 0.0);
  EXPECT_EQ(v, before);
}

// A daylight/HA table at 4–16 m, 0° and 20°, both emitter states, with every metric.
std::vector<records::PanelMetrics> SmoothRows(
    std::initializer_list<double> distances = {4.0, 8.0, 12.0, 16.0},
    std::initializer_list<double> angles = {0.0, 20.0}, const std::string& preset = "HA") {
  std::vector<records::PanelMetrics> rows;
  for (double dist : distances)
    for (double angle : angles)
      for (const char* emitter : {"off", "on"}) {
        rows.push_back(Row(dist, angle, preset, emitter));
        rows.back().temporal_std_m = 0.01;
        rows.back().normal_tilt_deg = angle;
        rows.back().panel_width_m = 1.0;
      }
  return rows;
}

// Only the window's metrics are smoothed: a disparity offset's surface whose every metric is a
// trend plus draws (seed 4242) keeps its median, spreads and valid share node for node, while
// its width comes nearer the trend, and the node at the offset's neutral value stays the base.
TEST(Smooth, OnlyTheWindowsMetricsAndNeverTheNeutralNode) {
  Design d;
  std::string why;
  ASSERT_TRUE(BuildDesign(SmoothRows(), &d, &why)) << why;
  ASSERT_EQ(d.num_metrics(), kNumMetrics);
  Simulations s;
  s.metrics = d.metrics;
  const int kk = d.num_metrics();
  s.base.assign(d.real.size(), 0.0);
  for (int c = 0; c < d.num_cells(); ++c) s.depth_m.push_back(d.cells[c].distance_m);
  Candidate offset;
  for (const Candidate& c : DefaultCandidates())
    if (c.effect == "disparity_offset") offset = c;
  ASSERT_EQ(offset.axes.size(), 1u);
  const Axis& axis = offset.axes[0];
  const int n = static_cast<int>(axis.nodes.size());
  int neutral = -1;
  for (int j = 0; j < n; ++j)
    if (IsNeutral(offset, {axis.nodes[j]})) neutral = j;
  ASSERT_GE(neutral, 0);
  Surface surf;
  surf.candidate = offset;
  surf.num_nodes = n;
  surf.table.assign(d.real.size() * n, 0.0);
  std::mt19937 rng(4242);
  std::normal_distribution<double> draw(0.0, 1.0);
  std::vector<double> trend(surf.table.size());
  for (int c = 0; c < d.num_cells(); ++c)
    for (int k = 0; k < kk; ++k)
      for (int j = 0; j < n; ++j) {
        const size_t i = (static_cast<size_t>(c) * kk + k) * n + j;
        const double scale = NoiseShape(d.metrics[k], s.depth_m[c]) * 0.01;
        trend[i] = 0.05 * axis.nodes[j] * scale * 100;
        surf.table[i] = trend[i] + (j == neutral ? 0.0 : scale * draw(rng));
      }
  s.surfaces.push_back(surf);
  SmoothSurfaces(d, &s);
  // The width and the plane's spread (window metrics) come closer to their trend; the median,
  // the temporal spread and the valid share keep their nodes.
  EXPECT_TRUE(InfoOf(kPlaneStd).window);
  EXPECT_FALSE(InfoOf(kTemporalStd).window || InfoOf(kValidPct).window);
  std::map<int, std::pair<double, double>> sq;  // metric → raw, smoothed
  for (int c = 0; c < d.num_cells(); ++c)
    for (int k = 0; k < kk; ++k)
      for (int j = 0; j < n; ++j) {
        const size_t i = (static_cast<size_t>(c) * kk + k) * n + j;
        if (!InfoOf(d.metrics[k]).window || j == neutral) {
          EXPECT_EQ(s.surfaces[0].table[i], surf.table[i]) << InfoOf(d.metrics[k]).name;
          continue;
        }
        auto& [raw, smooth] = sq[d.metrics[k]];
        raw += (surf.table[i] - trend[i]) * (surf.table[i] - trend[i]);
        smooth += (s.surfaces[0].table[i] - trend[i]) * (s.surfaces[0].table[i] - trend[i]);
      }
  for (int metric : {kPanelWidth, kPlaneStd}) {
    EXPECT_GT(sq[metric].first, 0) << InfoOf(metric).name;
    EXPECT_LT(sq[metric].second, 0.7 * sq[metric].first) << InfoOf(metric).name;
  }
}

// A range law's window metrics averaged over placement: a disparity offset whose width is the
// panel's 1 m window in whole pixels at the measured depth (a sawtooth of one pixel's period:
// 2.5 % of the distance at 16 m, f = 640 px). Over panels placed off by 3 % of their distance
// the width's departure from the neutral node is that sawtooth's mean; the averaged surface comes
// within half the raw nodes' error of it. The median and the neutral node stay as simulated, a
// candidate that is not a range law and a table without placement scatter are left alone.
TEST(Smooth, ARangeLawsWindowIsAveragedOverPlacement) {
  Design d;
  std::string why;
  ASSERT_TRUE(BuildDesign(SmoothRows(), &d, &why)) << why;
  Simulations s;
  s.metrics = d.metrics;
  const int kk = d.num_metrics();
  s.base.assign(d.real.size(), 0.0);
  for (int c = 0; c < d.num_cells(); ++c)
    s.depth_m.push_back(d.cells[c].distance_m * (1 + 0.003 * d.cells[c].angle_deg));
  const auto width_at = [](double z) { return std::round(640.0 / z) * z / 640.0; };
  const double rel = 0.03, fb = 58.0;
  const auto expected_at = [&](double z) {  // the width's mean over placements N(0, rel·z)
    double sum = 0, weights = 0;
    for (int i = -400; i <= 400; ++i) {
      const double e = i / 100.0, w = std::exp(-0.5 * e * e);
      sum += w * width_at(z * (1 + rel * e));
      weights += w;
    }
    return sum / weights;
  };
  Surface surf;
  for (const Candidate& c : DefaultCandidates())
    if (c.effect == "disparity_offset") surf.candidate = c;
  ASSERT_TRUE(surf.candidate.range_law);
  const Axis& axis = surf.candidate.axes[0];
  const int n = static_cast<int>(axis.nodes.size());
  int neutral = -1;
  for (int j = 0; j < n; ++j)
    if (IsNeutral(surf.candidate, {axis.nodes[j]})) neutral = j;
  ASSERT_GE(neutral, 0);
  surf.num_nodes = n;
  surf.table.assign(d.real.size() * n, 0.0);
  std::vector<double> measured(static_cast<size_t>(d.num_cells()) * n);
  for (int c = 0; c < d.num_cells(); ++c)
    for (int j = 0; j < n; ++j) {
      const double z = s.depth_m[c], zm = fb / (fb / z + axis.nodes[j]);
      measured[static_cast<size_t>(c) * n + j] = zm;
      for (int k = 0; k < kk; ++k) {
        double& v = surf.table[(static_cast<size_t>(c) * kk + k) * n + j];
        if (d.metrics[k] == kMedianBias) v = zm - z;
        if (d.metrics[k] == kPanelWidth) v = width_at(zm);
        // The plane's spread, a window metric that follows the depth itself: kept as it is.
        if (d.metrics[k] == kPlaneStd) v = 2 * std::log(zm / z) + 0.05 * width_at(zm);
      }
    }
  std::vector<double> rel_of_cell(d.num_cells(), rel);
  const Surface out = AverageOverPlacement(d, s, surf, rel_of_cell);
  double raw_sq = 0, averaged_sq = 0;
  for (int c = 0; c < d.num_cells(); ++c)
    for (int k = 0; k < kk; ++k) {
      const double* in = &surf.table[(static_cast<size_t>(c) * kk + k) * n];
      const double* av = &out.table[(static_cast<size_t>(c) * kk + k) * n];
      EXPECT_EQ(av[neutral], in[neutral]);
      if (d.metrics[k] != kPanelWidth) {
        for (int j = 0; j < n; ++j) EXPECT_EQ(av[j], in[j]) << InfoOf(d.metrics[k]).name;
        continue;
      }
      const double e0 = expected_at(measured[static_cast<size_t>(c) * n + neutral]);
      for (int j = 0; j < n; ++j) {
        if (j == neutral) continue;
        const double want = expected_at(measured[static_cast<size_t>(c) * n + j]) - e0;
        raw_sq += std::pow(in[j] - in[neutral] - want, 2);
        averaged_sq += std::pow(av[j] - av[neutral] - want, 2);
      }
    }
  EXPECT_GT(raw_sq, 0);
  EXPECT_LT(averaged_sq, 0.5 * raw_sq);
  // Not a range law, or no placement scatter: as simulated.
  Surface tilt = surf;
  for (const Candidate& c : DefaultCandidates())
    if (c.effect == "panel_tilt") tilt.candidate = c;
  ASSERT_FALSE(tilt.candidate.range_law);
  EXPECT_EQ(AverageOverPlacement(d, s, tilt, rel_of_cell).table, tilt.table);
  EXPECT_EQ(AverageOverPlacement(d, s, surf, std::vector<double>(d.num_cells(), 0.0)).table,
            surf.table);
}

// Two terms that move the window through the measured depth read it at their joint depth (fit.h,
// 1a). A disparity offset δ and a drift of rate r move the median by −δ·D²/fb and −0.15·r·D²/fb;
// the valid share follows the window alone, convex in the read-near share as a window that
// takes in more background the further it grows, H = −400·(ΔZ/Z)² points (reading far: none),
// and the drift alone raises log temporal_std by r. Each surface holds its own term's H, as a
// simulation does. A table made with δ = 0.15 px and r = 0.6 px/s (draws of seed 31) holds H at
// their joint depth, 0.42 and 0.75 points beyond the sum of each alone at 12 and 16 m. The fit
// started from nothing recovers both within 10 %, the two-term prediction of the valid share is
// H at the joint depth, one term alone is its own surface. With the terms' window departures
// added (FitSettings::joint_window false, the default), the same fit reads the offset more than
// 20 % high (0.233 px); its copy with the joint window (GapModel::JointWindow), refitting the
// offset's fit beside the drift's as the diagnosis reads a selection beside a named effect,
// reads both within 10 %.
TEST(Window, TermsThatMoveTheWindowReadItAtTheirJointDepth) {
  const double fb = 60.8, delta = 0.15, rate = 0.6;
  const auto offset_m = [&](double d, double dist) { return -d * dist * dist / fb; };
  const auto drift_m = [&](double r, double dist) { return -0.15 * r * dist * dist / fb; };
  const auto window = [](double m, double dist) {
    return -400.0 * std::pow(std::min(0.0, m) / dist, 2);
  };
  std::vector<records::PanelMetrics> rows = ArticleGrid();
  std::mt19937 rng(31);
  std::normal_distribution<double> unit(0.0, 1.0);
  for (auto& r : rows) {
    const double dist = r.distance_m, m = offset_m(delta, dist) + drift_m(rate, dist);
    r.median_m = dist + m + 0.002 * unit(rng);
    r.mean_m = r.median_m + 0.01 + 0.002 * unit(rng);
    r.valid_pct = 50 + window(m, dist) + 0.05 * unit(rng);
    r.temporal_std_m = 0.01 * std::exp(rate + 0.005 * unit(rng));
  }
  Design d;
  std::string why;
  ASSERT_TRUE(BuildDesign(rows, &d, &why)) << why;
  const int kk = d.num_metrics();
  int k_valid = -1, k_median = -1, k_temporal = -1;
  for (int k = 0; k < kk; ++k) {
    if (d.metrics[k] == kValidPct) k_valid = k;
    if (d.metrics[k] == kMedianBias) k_median = k;
    if (d.metrics[k] == kTemporalStd) k_temporal = k;
  }
  ASSERT_TRUE(k_valid >= 0 && k_median >= 0 && k_temporal >= 0);
  Simulations s;
  s.metrics = d.metrics;
  for (int c = 0; c < d.num_cells(); ++c) s.depth_m.push_back(d.cells[c].distance_m);
  s.base.resize(d.real.size());
  for (int c = 0; c < d.num_cells(); ++c)
    for (int k = 0; k < kk; ++k) {
      const size_t o = static_cast<size_t>(c) * kk + k;
      s.base[o] = k == k_median ? 0.0 : k == k_valid ? 50.0 : k == k_temporal ? std::log(0.01)
                                                                               : d.real[o];
    }
  s.jac_log_sigma.assign(s.base.size(), 0.0);
  s.jac_logit_p.assign(s.base.size(), 0.0);
  int i_offset = -1, i_drift = -1;
  for (const Candidate& cand : DefaultCandidates()) {
    if (cand.effect != "disparity_offset" && cand.effect != "temporal_drift") continue;
    const bool is_offset = cand.effect == "disparity_offset";
    ASSERT_TRUE(cand.moves_window) << cand.effect;
    (is_offset ? i_offset : i_drift) = static_cast<int>(s.surfaces.size());
    Surface surf;
    surf.candidate = cand;
    surf.num_nodes = static_cast<int>(cand.axes[0].nodes.size());
    surf.table.assign(s.base.size() * surf.num_nodes, 0.0);
    for (int c = 0; c < d.num_cells(); ++c)
      for (int j = 0; j < surf.num_nodes; ++j) {
        const double v = cand.axes[0].nodes[j], dist = d.cells[c].distance_m;
        const double m = is_offset ? offset_m(v, dist) : drift_m(v, dist);
        for (int k = 0; k < kk; ++k) {
          const size_t o = static_cast<size_t>(c) * kk + k;
          double dep = 0;
          if (k == k_median) dep = m;
          if (k == k_valid) dep = window(m, dist);
          if (k == k_temporal && !is_offset) dep = v;
          surf.table[o * surf.num_nodes + j] = s.base[o] + dep;
        }
      }
    s.surfaces.push_back(surf);
  }
  const NoiseEstimate noise = EstimateNoise(d, s);
  FitSettings fs;
  fs.joint_window = true;
  const std::vector<char> all(d.num_cells(), 1);
  const std::vector<Term> terms{{i_offset, Scope::kShared, {}}, {i_drift, Scope::kShared, {}}};
  {
    const GapModel model(d, s, noise, fs);
    ASSERT_TRUE(model.SharesWindow(terms));
    const ModelFit fit = FitTerms(model, terms, all);
    ASSERT_TRUE(fit.success) << fit.message;
    const double got_delta = fit.terms[0].values[0][0], got_rate = fit.terms[1].values[0][0];
    std::printf("joint window: offset %.4f px, drift %.4f px/s\n", got_delta, got_rate);
    EXPECT_NEAR(got_delta, delta, 0.1 * delta);
    EXPECT_NEAR(got_rate, rate, 0.1 * rate);
    ModelFit truth = fit;
    truth.terms[0].values[0][0] = delta;
    truth.terms[1].values[0][0] = rate;
    for (auto& n : truth.nuisance) n = {0, 0};
    const std::vector<double> mu = model.Predict(truth);
    for (int c = 0; c < d.num_cells(); ++c) {
      const double dist = d.cells[c].distance_m;
      const double joint = window(offset_m(delta, dist) + drift_m(rate, dist), dist);
      const double added = window(offset_m(delta, dist), dist) + window(drift_m(rate, dist), dist);
      const double got = mu[static_cast<size_t>(c) * kk + k_valid] - 50.0;
      EXPECT_NEAR(got, joint, 0.1 * std::fabs(joint) + 0.02) << dist << " m";
      if (dist >= 12) {
        EXPECT_GT(std::fabs(joint - added), 0.3) << dist << " m";
      }
    }
    ModelFit alone = truth;  // one term: its own surface
    alone.terms.pop_back();
    const std::vector<double> mu1 = model.Predict(alone);
    for (int c = 0; c < d.num_cells(); ++c) {
      const size_t o = static_cast<size_t>(c) * kk + k_valid;
      const double u = delta;
      EXPECT_DOUBLE_EQ(mu1[o] - 50.0, model.Delta(terms[0], &u, o)) << d.cells[c].distance_m;
    }
  }
  fs.joint_window = false;  // the default: the terms' window departures add
  const GapModel added(d, s, noise, fs);
  ASSERT_FALSE(added.SharesWindow(terms));
  const ModelFit fit = FitTerms(added, terms, all);
  ASSERT_TRUE(fit.success) << fit.message;
  std::printf("windows added: offset %.4f px, drift %.4f px/s\n", fit.terms[0].values[0][0],
              fit.terms[1].values[0][0]);
  EXPECT_GT(std::fabs(fit.terms[0].values[0][0] - delta), 0.2 * delta);
  // The selection read beside a named effect (diagnose.cpp, what the selection reads were it
  // the cause): the default model's copy with the joint window, started from each term's fit
  // alone, reads the offset at its size; the default model itself reads it high.
  const ModelFit offset_alone = FitTerms(added, {terms[0]}, all);
  const ModelFit drift_alone = FitTerms(added, {terms[1]}, all);
  ASSERT_TRUE(offset_alone.success && drift_alone.success);
  const GapModel joint = added.JointWindow();
  ASSERT_TRUE(joint.SharesWindow(terms));
  const ModelFit beside = FitBeside(joint, offset_alone, drift_alone.terms[0], all);
  ASSERT_TRUE(beside.success) << beside.message;
  EXPECT_NEAR(beside.terms[0].values[0][0], delta, 0.1 * delta);
  EXPECT_NEAR(beside.terms[1].values[0][0], rate, 0.1 * rate);
  const ModelFit beside_added = FitBeside(added, offset_alone, drift_alone.terms[0], all);
  ASSERT_TRUE(beside_added.success) << beside_added.message;
  EXPECT_GT(std::fabs(beside_added.terms[0].values[0][0] - delta), 0.2 * delta);
}

TEST(Json, EscapesAndWritesNullForNonFinite) {
  JsonWriter w;
  w.BeginObject().String("a\"b", "x\ny").Number("n", NAN).BeginArray("v").Number(1.5).EndArray();
  w.EndObject();
  EXPECT_EQ(w.Text(), "{\n  \"a\\\"b\": \"x\\ny\",\n  \"n\": null,\n  \"v\": [\n    1.5\n  ]\n}\n");
}

TEST(Candidates, EveryRegisteredEffectHasAValidGrid) {
  const auto all = DefaultCandidates();
  EXPECT_EQ(all.size(), sim::EffectRegistry().size());
  std::string why;
  for (const Candidate& c : all) EXPECT_TRUE(c.IsValid(&why)) << why;
  std::vector<Candidate> some;
  ASSERT_TRUE(SelectCandidates("depth_scale,region_spill", &some, &why)) << why;
  EXPECT_EQ(some.size(), 2u);
  EXPECT_FALSE(SelectCandidates("depth_scale,lens_flare", &some, &why));
  EXPECT_NE(why.find("lens_flare"), std::string::npos);
}

// p with one registered effect added.
sim::SimParams WithEffect(const sim::SimParams& p, const sim::EffectSpec& effect) {
  sim::SimParams q = p;
  std::string why;
  EXPECT_TRUE(sim::BuildDepartures({effect}, &q.departures, &why)) << why;
  return q;
}

// The signature tests' cell.
sim::Cell SignatureCell(double distance_m, double angle_deg, const std::string& preset,
                        bool emitter_on) {
  sim::Cell c;
  c.distance_m = distance_m;
  c.angle_deg = angle_deg;
  c.preset = preset;
  c.emitter_on = emitter_on;
  c.name = sim::CellName(c);
  return c;
}

// region_spill: the region reaches w whole pixels past the panel's outline onto a background at
// r times the panel's depth. Its signature: more pixels, a far tail (mean − median), a wider
// panel; none at w = 0; and the whole spill inside the rendered window up to its 5 px bound.
TEST(RegionSpill, SignatureInTheMetrics) {
  const sim::SimParams p = FallbackSensor(5, 0.2);
  const sim::Cell c = SignatureCell(12, 20, "HD", false);
  sim::MetricsParams mp;
  mp.frames = 5;
  auto with = [&](double w, double r) {
    return sim::SimulateMetrics(
        WithEffect(p, {"region_spill", {{"width_px", w}, {"background_rel", r}}}), c, mp);
  };
  const auto base = sim::SimulateMetrics(p, c, mp);
  const auto none = with(0, 2);
  const auto spill = with(4, 1.8);
  EXPECT_EQ(none.region_px, base.region_px);
  EXPECT_DOUBLE_EQ(none.metrics.mean_m, base.metrics.mean_m);
  const double side = std::sqrt(static_cast<double>(base.region_px));
  EXPECT_NEAR(std::sqrt(static_cast<double>(spill.region_px)), side + 8, 1.5);
  EXPECT_GT(spill.metrics.mean_m - spill.metrics.median_m,
            base.metrics.mean_m - base.metrics.median_m + 0.3);
  EXPECT_GT(spill.metrics.panel_width_m, base.metrics.panel_width_m + 0.2);
  EXPECT_GT(spill.metrics.plane_std_m, base.metrics.plane_std_m);
  // The 5 px bound: the metrics-only window holds the whole region (same as a full frame's).
  const sim::SimParams q =
      WithEffect(p, {"region_spill", {{"width_px", 5}, {"background_rel", 2}}});
  const auto windowed = sim::SimulateMetrics(q, c, mp);
  const sim::StereoSim full(q, c);
  EXPECT_EQ(static_cast<size_t>(windowed.region_px),
            full.RegionPixels(0.5, nullptr, &windowed.window).size());
  // A fractional width is floored to whole pixels.
  EXPECT_EQ(with(4.7, 1.8).region_px, spill.region_px);
}

// emitter_gain scales the texture the projector adds: with the emitter off a recording is the
// same to the bit whatever the gain; with it on at 4 m (within its reach) a gain of 0 gives the
// emitter-off valid share, and a larger gain more valid pixels; the depths do not move.
TEST(EmitterGain, SignatureInTheMetrics) {
  const sim::SimParams p = FallbackSensor(9, 0.6);
  sim::MetricsParams mp;
  mp.frames = 5;
  auto at = [&](double gain, bool on) {
    const sim::Cell c = SignatureCell(4, 0, sim::Cell().preset, on);
    return sim::SimulateMetrics(WithEffect(p, {"emitter_gain", {{"gain", gain}}}), c, mp).metrics;
  };
  const auto off = at(1, false), off_zero = at(0, false);
  EXPECT_DOUBLE_EQ(off_zero.valid_pct, off.valid_pct);
  EXPECT_DOUBLE_EQ(off_zero.median_m, off.median_m);
  const auto on = at(1, true), on_zero = at(0, true), on_three = at(3, true);
  EXPECT_GT(on.valid_pct, off.valid_pct + 3) << "the configured emitter adds valid pixels at 4 m";
  EXPECT_NEAR(on_zero.valid_pct, off.valid_pct, 2.0);  // another seed's draw: within noise
  EXPECT_GT(on_three.valid_pct, on.valid_pct + 3);
  EXPECT_NEAR(on_three.median_m, on.median_m, 0.01);
}


// Edge mixing's spread peaks at small strengths (mixed pixels near the panel's plane stay in
// the region and widen it; mixed further, they leave as background), so a grid with nothing
// between 0 and 0.3 reads a strength of 0.09 as the base: the fit then took it for a free
// small correction and its simulation widened the spread many times over. Between the grid's
// first nodes the interpolated log plane_std comes within half of what the simulation departs
// from the base, at widths of 1 and 2 px (seed 5).
TEST(Candidates, EdgeMixingsGridResolvesItsSmallStrengths) {
  Design d;
  std::string why;
  ASSERT_TRUE(BuildDesign(SmoothRows(), &d, &why)) << why;
  sim::SimParams p;
  p.seed = 5;
  Candidate em;
  for (const Candidate& c : DefaultCandidates())
    if (c.effect == "edge_mixing") em = c;
  ASSERT_EQ(em.axes.size(), 2u);
  SimulateOptions options;
  const Simulations s = SimulateDesign(p, d, {em}, options);
  const int kk = d.num_metrics();
  const Axis& width = em.axes[0];
  const Axis& strength = em.axes[1];
  const int n1 = static_cast<int>(strength.nodes.size());
  const double t = 0.09;
  for (int wi : {0, 1}) {
    sim::SimParams q = p;
    ASSERT_TRUE(sim::BuildDepartures({SpecAt(em, {width.nodes[wi], t})}, &q.departures, &why))
        << why;
    const std::vector<double> v = SimulateValues({q}, d, options);
    double err = 0, departure = 0;
    for (int c = 0; c < d.num_cells(); ++c)
      for (int k = 0; k < kk; ++k) {
        if (d.metrics[k] != kPlaneStd) continue;
        const size_t o = static_cast<size_t>(c) * kk + k;
        const double* row = &s.surfaces[0].table[o * s.surfaces[0].num_nodes + wi * n1];
        err = std::max(err, std::fabs(Pchip(strength.nodes.data(), row, n1, t) - v[o]));
        departure = std::max(departure, std::fabs(v[o] - s.base[o]));
      }
    EXPECT_GT(departure, 0.02) << "width " << width.nodes[wi];
    EXPECT_LT(err, 0.5 * departure) << "width " << width.nodes[wi];
  }
}

// Past its peak, edge mixing's departures fall steeply: mixed pixels leave the region as the
// strength grows. Simulated at 20 seeds (`simulate --metrics-only`, the article's protocol,
// width 3 px, all 32 recordings at a distance), normal_tilt_deg at 16 m departs by +2.09° at
// 0.3, +0.90° at 0.4, +0.67° at 0.5 and +0.55° at 0.65; log plane_std at 12 m by 0.059, 0.037,
// 0.023 and 0.009. With nothing between 0.3 and 0.65 the interpolation followed the fall too
// late, and the fits read a strength of 0.5 as 0.72 to 0.80 (the withheld suite, seeds
// 601-605: the model at 0.5 departed further than the table, as at 0.3). The far HD cells'
// interpolated tilt, summed over four seeds, against the same cells simulated at each strength
// with a seed of their own (not the surfaces'): 69 %, 29 % and 23 % off at 0.35, 0.45 and 0.57
// (the grid without 0.4 and 0.5: 121 %, 295 % and 133 %). Between the new nodes it must come
// within half; between 0.3 and 0.4, where the fall is steepest and still coarse, within the
// departure itself.
TEST(Candidates, EdgeMixingsGridFollowsItsFallPastThePeak) {
  // The high-density preset at 12 and 16 m, where the fall is steepest.
  Design d;
  std::string why;
  ASSERT_TRUE(BuildDesign(SmoothRows({12.0, 16.0}, {0.0, 10.0, 20.0}, "HD"), &d, &why)) << why;
  Candidate em;
  for (const Candidate& c : DefaultCandidates())
    if (c.effect == "edge_mixing") em = c;
  ASSERT_EQ(em.axes.size(), 2u);
  const Axis& width = em.axes[0];
  const Axis& strength = em.axes[1];
  const int n1 = static_cast<int>(strength.nodes.size());
  const int wi = static_cast<int>(
      std::find(width.nodes.begin(), width.nodes.end(), 3.0) - width.nodes.begin());
  ASSERT_LT(wi, static_cast<int>(width.nodes.size()));
  const int kk = d.num_metrics();
  const std::vector<double> at{0.35, 0.45, 0.57}, tolerance{1.0, 0.5, 0.5};
  std::vector<double> interp(at.size(), 0.0), simulated(at.size(), 0.0);
  SimulateOptions options;  // 10 frames a recording, as the diagnosis simulates
  for (std::uint64_t seed : {17, 23, 31, 37}) {
    // The article's scene and calibrated sensor: where the fall lies moves with the scenario's
    // noise, its hole odds and the frames pooled.
    sim::SimParams p = test_support::ArticleSimParams();
    p.seed = seed;
    const Simulations s = SimulateDesign(p, d, {em}, options);
    for (size_t i = 0; i < at.size(); ++i) {
      sim::SimParams q = p;
      q.sensor = s.sensor;  // every scenario listed, as the surfaces were simulated
      q.seed = seed + 1000;  // the truth's draws are not the surfaces'
      ASSERT_TRUE(sim::BuildDepartures({SpecAt(em, {3.0, at[i]})}, &q.departures, &why)) << why;
      const std::vector<double> v = SimulateValues({q}, d, options);
      for (int c = 0; c < d.num_cells(); ++c)
        for (int k = 0; k < kk; ++k) {
          if (d.metrics[k] != kNormalTilt) continue;
          const size_t o = static_cast<size_t>(c) * kk + k;
          const double* row = &s.surfaces[0].table[o * s.surfaces[0].num_nodes + wi * n1];
          interp[i] += Pchip(strength.nodes.data(), row, n1, at[i]) - s.base[o];
          simulated[i] += v[o] - s.base[o];
        }
    }
  }
  for (size_t i = 0; i < at.size(); ++i) {
    EXPECT_GT(simulated[i], 0) << "at " << at[i];
    EXPECT_LT(std::fabs(interp[i] - simulated[i]), tolerance[i] * std::fabs(simulated[i]))
        << "at " << at[i] << ": interpolated " << interp[i] << ", simulated " << simulated[i];
  }
}

}  // namespace
}  // namespace depthbias::gap

