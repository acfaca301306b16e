#include "gap/simulations.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <optional>
#include <stdexcept>

#include "common/hash.h"
#include "gap/smooth.h"

namespace depthbias::gap {
namespace {

double Logit(double p) {
  p = std::clamp(p, 1e-4, 1 - 1e-4);
  return std::log(p / (1 - p));
}
double Logistic(double x) { return 1.0 / (1.0 + std::exp(-x)); }

// The sensor with each listed scenario's log σ_d and logit p moved by the given steps.
sim::SensorParams Nudged(const sim::SensorParams& s, double d_log_sigma, double d_logit_p) {
  sim::SensorParams out = s;
  for (auto& sc : out.scenarios) {
    sc.sigma_d_px = sc.sigma_d_px * std::exp(d_log_sigma);
    sc.invalid_prob = Logistic(Logit(sc.invalid_prob) + d_logit_p);
  }
  return out;
}

// Fills every non-finite entry of one observation's node values with the nearest node's (in
// index steps over the grid) finite value; all non-finite stays so.
void FillGaps(const std::vector<int>& shape, double* v) {
  const int n = static_cast<int>(shape.size() == 1 ? shape[0] : shape[0] * shape[1]);
  const int n1 = shape.size() == 1 ? 1 : shape[1];
  bool any_gap = false;
  for (int i = 0; i < n; ++i) any_gap = any_gap || !std::isfinite(v[i]);
  if (!any_gap) return;
  std::vector<double> out(v, v + n);
  for (int i = 0; i < n; ++i) {
    if (std::isfinite(v[i])) continue;
    int best = -1, best_d = 1 << 30;
    for (int j = 0; j < n; ++j) {
      if (!std::isfinite(v[j])) continue;
      const int d = std::abs(i / n1 - j / n1) + std::abs(i % n1 - j % n1);
      if (d < best_d) best_d = d, best = j;
    }
    if (best >= 0) out[i] = v[best];
  }
  std::copy(out.begin(), out.end(), v);
}

// The test point a recording's name (sim::CellName, at its nominal distance and angle) names:
// the name without its emitter and preset, which one placement of the panel shares.
std::string TestPointOf(const sim::Cell& c) {
  std::string k = c.name;
  for (const std::string token : {"_emitter-on", "_emitter-off"}) {
    const size_t at = k.find(token);
    if (at != std::string::npos) k.erase(at, token.size());
  }
  if (k.size() >= c.preset.size() && k.compare(k.size() - c.preset.size(), std::string::npos,
                                               c.preset) == 0)
    k.erase(k.size() - c.preset.size());
  return k;
}

}  // namespace

bool SimulateOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (frames < 1 || frames > 100000) return fail("frames must be in [1, 100000]");
  if (threads < 1 || threads > 256) return fail("threads must be in [1, 256]");
  if (!(region_margin_px >= 0)) return fail("region_margin_px must be >= 0");
  if (!(step_log_sigma > 0 && step_log_sigma < 1) || !(step_logit_p > 0 && step_logit_p < 3))
    return fail("nuisance steps must be in (0, 1) (log σ_d) and (0, 3) (logit p)");
  if (!(shift_px >= 0 && shift_px <= 10)) return fail("shift_px must be in [0, 10]");
  if (!(placement_probe >= 0 && placement_probe <= 0.2))
    return fail("placement_probe must be in [0, 0.2]");
  if (!(lateral_phase_px >= 0 && lateral_phase_px <= 10))
    return fail("lateral_phase_px must be in [0, 10]");
  return true;
}

Design LateralPhases(const Design& d, const sim::SimParams& base, double shift_px) {
  Design out = d;
  const double px_deg = 180 / M_PI / base.sensor.focal_px();
  for (sim::Cell& c : out.cells)
    c.angle_deg +=
        shift_px * px_deg * (2 * common::UniformOf(base.seed, "lateral|" + TestPointOf(c)) - 1);
  return out;
}

bool Simulations::Matches(const Design& design) const {
  if (metrics != design.metrics || cell_names.size() != design.cells.size()) return false;
  for (size_t c = 0; c < cell_names.size(); ++c)
    if (cell_names[c] != design.cells[c].name) return false;
  return true;
}

sim::SensorParams ListScenarios(const sim::SensorParams& sensor, const Design& design) {
  sim::SensorParams out = sensor;
  out.scenarios.clear();
  for (const std::string& name : design.scenario_names) {
    const size_t slash = name.find('/');
    out.scenarios.push_back(sensor.Scenario(name.substr(0, slash), name.substr(slash + 1)));
  }
  return out;
}

namespace {

// SimulateValues at each width of spills_px, or at the parameters' own width when it is empty;
// with valid_only, the valid share alone is measured (sim::MetricsParams::valid_share_only), the
// other metrics left missing.
std::vector<std::vector<double>> SimulateTables(const std::vector<sim::SimParams>& params,
                                                const Design& d, const SimulateOptions& options,
                                                const std::vector<double>& spills_px,
                                                std::vector<double>* depth_m,
                                                bool valid_only = false) {
  const int k_count = d.num_metrics();
  const size_t widths = spills_px.empty() ? 1 : spills_px.size();
  std::vector<std::vector<double>> out(
      widths, std::vector<double>(static_cast<size_t>(d.num_cells()) * k_count, NAN));
  if (depth_m) depth_m->assign(d.cells.size(), NAN);
  sim::MetricsParams mp;
  mp.frames = options.frames;
  mp.threads = options.threads;
  mp.region_margin_px = options.region_margin_px;
  mp.valid_share_only = valid_only;
  const int groups = params.size() == 1 ? 1 : d.num_scenarios();
  if (params.empty() || (params.size() != 1 && static_cast<int>(params.size()) != groups))
    throw std::invalid_argument("SimulateValues: one parameter set, or one per scenario");
  for (int g = 0; g < groups; ++g) {
    // Identical cells (one name: one seed, one result) are simulated once.
    std::vector<sim::Cell> cells;
    std::vector<int> index;  // [cell of the design] → its simulated cell, −1 if not in g
    std::map<std::string, int> seen;
    index.assign(d.num_cells(), -1);
    for (int c = 0; c < d.num_cells(); ++c) {
      if (groups > 1 && d.scenario[c] != g) continue;
      const auto it = seen.emplace(d.cells[c].name, static_cast<int>(cells.size())).first;
      if (it->second == static_cast<int>(cells.size())) cells.push_back(d.cells[c]);
      index[c] = it->second;
    }
    if (cells.empty()) continue;
    sim::SimParams p = params[g];
    p.dither_quantization = options.dither_quantization;
    const std::vector<std::vector<sim::CellMetricsResult>> by_width =
        sim::SimulateCellsMetricsSpills(
            p, cells, mp,
            spills_px.empty() ? std::vector<double>{p.departures.region_spill_px} : spills_px);
    for (size_t w = 0; w < widths; ++w) {
      const std::vector<sim::CellMetricsResult>& r = by_width[w];
      for (int c = 0; c < d.num_cells(); ++c) {
        const int i = index[c];
        if (i < 0) continue;
        if (depth_m && w == 0) (*depth_m)[c] = r[i].truth.panel_depth_m;
        if (!r[i].metrics.ok()) continue;
        for (int k = 0; k < k_count; ++k)
          out[w][static_cast<size_t>(c) * k_count + k] = MetricValue(r[i].metrics, d.metrics[k]);
      }
    }
  }
  return out;
}

}  // namespace

std::vector<double> SimulateValues(const std::vector<sim::SimParams>& params, const Design& d,
                                   const SimulateOptions& options, std::vector<double>* depth_m) {
  return std::move(SimulateTables(params, d, options, {}, depth_m)[0]);
}

std::vector<double> SimulateSelection(const std::vector<sim::SimParams>& params,
                                      const Design& d, const sim::SimParams& base,
                                      const SimulateOptions& options) {
  std::vector<double> v = SimulateValues(params, d, options);
  if (!(options.lateral_phase_px > 0)) return v;
  const std::vector<double> w =
      SimulateValues(params, LateralPhases(d, base, options.lateral_phase_px), options);
  for (size_t i = 0; i < v.size(); ++i)
    if (std::isfinite(v[i]) && std::isfinite(w[i])) v[i] = 0.5 * (v[i] + w[i]);
  return v;
}

std::vector<std::vector<double>> SimulateValuesSpills(const sim::SimParams& params,
                                                      const Design& d,
                                                      const SimulateOptions& options,
                                                      const std::vector<double>& spills_px) {
  if (spills_px.empty()) return {};
  return SimulateTables({params}, d, options, spills_px, nullptr);
}

Simulations SimulateDesign(const sim::SimParams& base_in, const Design& d,
                           const std::vector<Candidate>& candidates,
                           const SimulateOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("simulation options: " + why);
  for (const Candidate& c : candidates)
    if (!c.IsValid(&why)) throw std::invalid_argument(why);
  Simulations s;
  for (const sim::Cell& c : d.cells) s.cell_names.push_back(c.name);
  s.metrics = d.metrics;
  sim::SimParams base = base_in;
  base.sensor = ListScenarios(base_in.sensor, d);
  s.sensor = base.sensor;
  auto run = [&](const sim::SimParams& p, std::vector<double>* depth = nullptr) {
    ++s.runs;
    return SimulateValues({p}, d, options, depth);
  };
  s.base = run(base, &s.depth_m);
  // The valid share of an effect that moves the window, read with each test point's panel at a
  // lateral phase of its own (SimulateOptions::lateral_phase_px): the base moved alike, for its
  // departures.
  const size_t k_count = static_cast<size_t>(d.num_metrics());
  const auto valid_at = std::find(d.metrics.begin(), d.metrics.end(), kValidPct);
  const size_t valid_k = static_cast<size_t>(valid_at - d.metrics.begin());
  const bool lateral = options.lateral_phase_px > 0 && valid_at != d.metrics.end() &&
                       std::any_of(candidates.begin(), candidates.end(),
                                   [](const Candidate& c) { return c.moves_window; });
  const Design lateral_d = lateral ? LateralPhases(d, base, options.lateral_phase_px) : d;
  // Only the valid share of these runs is read: the metrics kernel is left out of them.
  auto valid_at_lateral = [&](const sim::SimParams& p) {
    ++s.runs;
    return std::move(SimulateTables({p}, lateral_d, options, {}, nullptr, true)[0]);
  };
  std::vector<double> base_lateral;
  if (lateral) base_lateral = valid_at_lateral(base);
  const size_t obs = s.base.size();

  // The calibration's Jacobian: every scenario nudged at once (each cell sees only its own).
  auto jacobian = [&](double d_sigma, double d_p, double step) {
    sim::SimParams plus = base, minus = base;
    plus.sensor = Nudged(base.sensor, d_sigma, d_p);
    minus.sensor = Nudged(base.sensor, -d_sigma, -d_p);
    const std::vector<double> a = run(plus), b = run(minus);
    std::vector<double> j(obs, 0.0);
    for (size_t i = 0; i < obs; ++i)
      if (std::isfinite(a[i]) && std::isfinite(b[i])) j[i] = (a[i] - b[i]) / (2 * step);
    return j;
  };
  s.jac_log_sigma = jacobian(options.step_log_sigma, 0, options.step_log_sigma);
  s.jac_logit_p = jacobian(0, options.step_logit_p, options.step_logit_p);
  if (options.replica) {
    sim::SimParams other = base;
    other.seed = base.seed + 1;
    s.replica = run(other);
  }
  if (options.shift_px > 0) {
    // A fraction of a pixel sideways changes no law of the camera's (0.07° of angle a pixel),
    // but which pixels see the panel's edges and which noise falls on it.
    Design shifted = d;
    const double px_deg = 180 / M_PI / base.sensor.focal_px();
    for (sim::Cell& c : shifted.cells)
      c.angle_deg += options.shift_px * px_deg *
                     (2 * common::UniformOf(base.seed, "phase|" + c.name) - 1);
    ++s.runs;
    s.shifted = SimulateValues({base}, shifted, options);
  }

  if (options.placement_probe > 0) {
    Design moved = d;
    for (sim::Cell& c : moved.cells) c.distance_m *= 1 + options.placement_probe;
    ++s.runs;
    s.moved = SimulateValues({base}, moved, options);
    s.moved_rel = options.placement_probe;
  }

  // A node that departs from a base without departures by the emitter's gain alone changes no
  // emitter-off cell (sim::Departures::OnlyEmitter): those are the base's, bit for bit, and only
  // the emitter-on cells are simulated.
  const bool base_plain = base.departures.OnlyEmitter();
  std::vector<char> emitter_on(d.cells.size(), 0);
  for (size_t c = 0; c < d.cells.size(); ++c) emitter_on[c] = d.cells[c].emitter_on;
  const bool any_on = std::find(emitter_on.begin(), emitter_on.end(), 1) != emitter_on.end();
  for (const Candidate& cand : candidates) {
    Surface surf;
    surf.candidate = cand;
    std::vector<int> shape;
    for (const Axis& a : cand.axes) shape.push_back(static_cast<int>(a.nodes.size()));
    surf.num_nodes = shape.size() == 1 ? shape[0] : shape[0] * shape[1];
    surf.table.assign(obs * surf.num_nodes, NAN);
    // Each node's parameters (none: the base's values).
    std::vector<std::optional<sim::SimParams>> at(surf.num_nodes);
    for (int node = 0; node < surf.num_nodes; ++node) {
      std::vector<double> values(shape.size());
      if (shape.size() == 1) {
        values[0] = cand.axes[0].nodes[node];
      } else {
        values[0] = cand.axes[0].nodes[node / shape[1]];
        values[1] = cand.axes[1].nodes[node % shape[1]];
      }
      if (IsNeutral(cand, values)) continue;
      sim::SimParams p = base;
      if (!sim::BuildDepartures({SpecAt(cand, values)}, &p.departures, &why))
        throw std::invalid_argument("candidate " + cand.effect + ": " + why);
      at[node] = std::move(p);
    }
    auto store = [&](int node, const std::vector<double>& v) {
      for (size_t i = 0; i < obs; ++i) surf.table[i * surf.num_nodes + node] = v[i];
    };
    std::vector<char> done(surf.num_nodes, 0);
    for (int node = 0; node < surf.num_nodes; ++node) {
      if (done[node]) continue;
      if (!at[node]) {
        store(node, s.base);
        continue;
      }
      const sim::SimParams& p = *at[node];
      if (base_plain && p.departures.OnlyEmitter()) {
        ++s.runs;
        std::vector<double> all(s.base.begin(), s.base.end());
        if (any_on) {
          const std::vector<double> on = SimulateValues({p}, Subset(d, emitter_on), options);
          for (size_t c = 0, j = 0; c < d.cells.size(); ++c) {
            if (!emitter_on[c]) continue;
            for (size_t k = 0; k < k_count; ++k) all[c * k_count + k] = on[j * k_count + k];
            ++j;
          }
        }
        store(node, all);
        continue;
      }
      // The nodes that differ from this one by the drawn region's width alone are simulated
      // with it (one sensor, footprint and plane per cell for all of them).
      std::vector<int> group{node};
      std::vector<double> spills{p.departures.region_spill_px};
      for (int other = node + 1; other < surf.num_nodes; ++other)
        if (!done[other] && at[other] && p.departures.SameButSpill(at[other]->departures)) {
          group.push_back(other);
          spills.push_back(at[other]->departures.region_spill_px);
        }
      std::vector<std::vector<double>> tables =
          group.size() == 1 ? std::vector<std::vector<double>>{run(p)}
                            : SimulateValuesSpills(p, d, options, spills);
      if (lateral && cand.moves_window && group.size() == 1) {
        const std::vector<double> at = valid_at_lateral(p);
        for (size_t c = 0; c < d.cells.size(); ++c) {
          const size_t o = c * k_count + valid_k;
          if (std::isfinite(at[o]) && std::isfinite(base_lateral[o]))
            tables[0][o] = s.base[o] + (at[o] - base_lateral[o]);
        }
      }
      if (group.size() > 1) s.runs += static_cast<int>(group.size());
      for (size_t g = 0; g < group.size(); ++g) {
        store(group[g], tables[g]);
        done[group[g]] = 1;
      }
    }
    for (size_t i = 0; i < obs; ++i) FillGaps(shape, &surf.table[i * surf.num_nodes]);
    s.surfaces.push_back(std::move(surf));
  }
  SmoothSurfaces(d, &s);
  return s;
}

double PchipSlope(const double* x, const double* y, int n, int j) {
  auto secant = [&](int k) { return (y[k + 1] - y[k]) / (x[k + 1] - x[k]); };
  if (j == 0) return secant(0);
  if (j == n - 1) return secant(n - 2);
  const double a = secant(j - 1), b = secant(j);
  if (a * b <= 0) return 0.0;
  const double ha = x[j] - x[j - 1], hb = x[j + 1] - x[j];
  const double w1 = 2 * hb + ha, w2 = hb + 2 * ha;
  return (w1 + w2) / (w1 / a + w2 / b);
}

double Pchip(const double* x, const double* y, int n, double t) {
  if (n == 1) return y[0];
  if (t <= x[0]) return y[0];
  if (t >= x[n - 1]) return y[n - 1];
  int i = static_cast<int>(std::upper_bound(x, x + n, t) - x) - 1;
  i = std::clamp(i, 0, n - 2);
  const double h = x[i + 1] - x[i], s = (t - x[i]) / h;
  const double m0 = PchipSlope(x, y, n, i) * h, m1 = PchipSlope(x, y, n, i + 1) * h;
  const double s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * y[i] + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * y[i + 1] +
         (s3 - s2) * m1;
}

}  // namespace depthbias::gap
