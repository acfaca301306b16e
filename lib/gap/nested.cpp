#include "gap/nested.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "gap/localize.h"
#include "gap/select.h"

namespace depthbias::gap {
namespace {

std::string Num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Level of a cell for a factor (0 distance, 1 angle, 2 preset, 3 light, 4 emitter) as text.
std::string LevelOf(const sim::Cell& c, int factor) {
  switch (factor) {
    case 0: return "distance " + Num(c.distance_m) + " m";
    case 1: return "angle " + Num(c.angle_deg) + "°";
    case 2: return "preset " + c.preset;
    case 3: return "light " + c.light;
    default: return std::string("emitter ") + (c.emitter_on ? "on" : "off");
  }
}

}  // namespace

Design Subset(const Design& d, const std::vector<char>& cells) {
  Design s;
  s.scenario_names = d.scenario_names;
  s.metrics = d.metrics;
  const int kk = d.num_metrics();
  for (int c = 0; c < d.num_cells(); ++c) {
    if (!cells[c]) continue;
    s.cells.push_back(d.cells[c]);
    s.row.push_back(d.row[c]);
    s.bag.push_back(d.bag[c]);
    s.scenario.push_back(d.scenario[c]);
    for (int k = 0; k < kk; ++k) s.real.push_back(d.real[static_cast<size_t>(c) * kk + k]);
  }
  return s;
}

namespace {

// One outer fold diagnosed without its cells.
struct FoldRun {
  NestedFold fold;
  std::vector<char> held;
  std::vector<double> zb, z0, z1, zs, zsc;
  bool ok = true;
  std::string message;
};

FoldRun RunFold(const Design& d, const Simulations& sims, const sim::SimParams& base,
                const DiagnoseParams& params, const std::vector<int>& fold, int num_folds,
                int f) {
  FoldRun out;
  const int kk = d.num_metrics();
  const size_t obs = d.real.size();
  std::vector<char> train(d.num_cells(), 0);
  out.held.assign(d.num_cells(), 0);
  NestedFold& nf = out.fold;
  for (int c = 0; c < d.num_cells(); ++c) {
    train[c] = fold[c] != f;
    out.held[c] = fold[c] == f;
    if (out.held[c] && nf.held.empty()) nf.held = LevelOf(d.cells[c], 0);
    nf.cells += out.held[c];
  }
  if (nf.cells == 0) return out;
  try {
    const NoiseEstimate noise = EstimateNoise(d, sims, train);
    const PlacementEstimate placement =
        params.placement ? EstimatePlacement(d, sims, noise, train, params.placement_alpha)
                         : PlacementEstimate();
    GapModel model(d, sims, noise, params.fit, &placement);
    const Selection sel = Select(model, train, fold, num_folds, params);
    if (!sel.success) throw std::invalid_argument(sel.message);
    for (const auto& s : sel.steps) nf.selected.push_back(s.effect);
    const std::vector<double> mu0 = model.Predict(sel.m0), mu1 = model.Predict(sel.current);
    nf.deviance_calibrated = model.DataDeviance(mu0, out.held);
    nf.deviance_selected = model.DataDeviance(mu1, out.held);
    out.zb = Scaled(model, sims.base);
    out.z0 = Scaled(model, mu0);
    out.z1 = Scaled(model, mu1);
    out.zs.assign(obs, NAN);
    out.zsc.assign(obs, NAN);
    try {
      const Design sub = Subset(d, out.held);
      SimulateOptions options = params.simulate;
      options.threads = 1;  // the folds run side by side
      // The held-out cells simulated with the fold's calibrated base, and with its selection.
      auto simulate = [&](const ModelFit& fit) {
        const std::vector<double> v = SimulateValues(
            SelectedParams(sims, base, fit, d.num_scenarios()), sub, options);
        std::vector<double> mu(obs, NAN);
        int i = 0;
        for (int c = 0; c < d.num_cells(); ++c) {
          if (!out.held[c]) continue;
          for (int k = 0; k < kk; ++k)
            mu[static_cast<size_t>(c) * kk + k] = v[static_cast<size_t>(i) * kk + k];
          ++i;
        }
        return mu;
      };
      const std::vector<double> mu = simulate(sel.current);
      out.zsc = sel.steps.empty() ? Scaled(model, mu) : Scaled(model, simulate(sel.m0));
      out.zs = Scaled(model, mu);
      nf.simulated = true;
    } catch (const std::exception& e) {
      out.message = "fold " + nf.held + ": not simulated: " + e.what();
    }
  } catch (const std::exception& e) {
    out.ok = false;
    out.message = "fold " + nf.held + ": " + e.what();
  }
  return out;
}

}  // namespace

Nested RunNested(const Design& d, const Simulations& sims, const sim::SimParams& base,
                 const DiagnoseParams& params, const std::vector<int>& fold, int num_folds,
                 const GapModel& full) {
  Nested n;
  const int kk = d.num_metrics();
  const size_t obs = d.real.size();
  n.cells.assign(d.num_cells(), 0);
  for (auto* z : {&n.z_baseline, &n.z_calibrated, &n.z_selected, &n.z_simulated,
                  &n.z_simulated_calibrated})
    z->assign(obs, NAN);
  // The folds side by side, as many at once as the simulation may use threads.
  std::vector<FoldRun> runs(num_folds);
  std::atomic<int> next{0};
  auto worker = [&] {
    for (int f = next++; f < num_folds; f = next++)
      runs[f] = RunFold(d, sims, base, params, fold, num_folds, f);
  };
  const int workers = std::max(1, std::min(params.simulate.threads, num_folds));
  std::vector<std::thread> pool;
  for (int i = 1; i < workers; ++i) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  bool all_simulated = true;
  for (FoldRun& run : runs) {
    if (run.fold.cells == 0) continue;
    if (!run.ok) {
      n.message = run.message;
      return n;
    }
    if (!run.fold.simulated) {
      all_simulated = false;
      n.message = run.message;
    }
    n.gain += run.fold.deviance_calibrated - run.fold.deviance_selected;
    for (int c = 0; c < d.num_cells(); ++c) {
      if (!run.held[c]) continue;
      n.cells[c] = 1;
      for (int k = 0; k < kk; ++k) {
        const size_t o = static_cast<size_t>(c) * kk + k;
        n.z_baseline[o] = run.zb[o];
        n.z_calibrated[o] = run.z0[o];
        n.z_selected[o] = run.z1[o];
        n.z_simulated[o] = run.zs[o];
        n.z_simulated_calibrated[o] = run.zsc[o];
      }
    }
    n.folds.push_back(std::move(run.fold));
  }
  n.baseline = Stat(full, n.z_baseline, n.cells);
  n.calibrated = Stat(full, n.z_calibrated, n.cells);
  n.selected = Stat(full, n.z_selected, n.cells);
  n.shrink_heldout_nested_pct = Shrink(n.baseline, n.selected);
  if (all_simulated) {
    n.simulated = Stat(full, n.z_simulated, n.cells);
    n.shrink_simulated_pct = Shrink(n.baseline, n.simulated);
    n.simulated_calibrated = Stat(full, n.z_simulated_calibrated, n.cells);
    n.gain_simulated = 0;
    for (size_t o = 0; o < obs; ++o) {
      const double a = n.z_simulated_calibrated[o], b = n.z_simulated[o];
      if (std::isfinite(a) && std::isfinite(b)) n.gain_simulated += a * a - b * b;
    }
  }
  n.run = true;
  return n;
}

std::vector<Unexplained> DescribeRest(const GapModel& m, const std::vector<double>& mu,
                                      const PlacementEstimate& pe, double alpha) {
  std::vector<Unexplained> out;
  const Design& d = m.design();
  const int kk = d.num_metrics();
  const std::vector<double> z = Scaled(m, mu);
  // Candidate groups of cells: every level of a factor, of a pair of factors, and every test
  // point.
  std::map<std::string, std::vector<int>> groups;
  for (int c = 0; c < d.num_cells(); ++c) {
    for (int f = 0; f < 5; ++f) {
      groups[LevelOf(d.cells[c], f)].push_back(c);
      for (int g = f + 1; g < 5; ++g)
        groups[LevelOf(d.cells[c], f) + " × " + LevelOf(d.cells[c], g)].push_back(c);
    }
    if (!pe.point.empty()) {
      const int t = pe.point[c];
      groups["test point " + pe.point_light[t] + " " + Num(pe.point_distance_m[t]) + " m " +
             Num(pe.point_angle_deg[t]) + "°"]
          .push_back(c);
    }
  }
  for (int k = 0; k < kk; ++k) {
    double total = 0;
    int n = 0;
    for (int c = 0; c < d.num_cells(); ++c) {
      const double v = z[static_cast<size_t>(c) * kk + k];
      if (std::isfinite(v)) total += v * v, ++n;
    }
    if (n == 0 || ChiSquareSurvival(total, n) >= alpha / kk) continue;
    // The group whose mean departure carries the most of the metric's Σz² for its size:
    // (share of Σz² its mean explains)² / (its share of the cells).
    double best_score = 0;
    std::string best_name;
    for (const auto& [name, cells] : groups) {
      double sum = 0;
      int count = 0;
      for (int c : cells) {
        const double v = z[static_cast<size_t>(c) * kk + k];
        if (std::isfinite(v)) sum += v, ++count;
      }
      if (count == 0) continue;
      const double share = sum * sum / count / total;
      const double score = share * share / (static_cast<double>(count) / n);
      if (score > best_score) best_score = score, best_name = name;
    }
    if (best_name.empty()) continue;
    Unexplained u;
    u.metric = InfoOf(d.metrics[k]).name;
    u.unit = InfoOf(d.metrics[k]).unit;
    u.where = best_name;
    // Size and form: weighted least squares of the residual on 1, D, D² (one at a time).
    double sw = 0, swr = 0, chi2 = 0, max_d = 0;
    double s[3] = {0, 0, 0}, sr[3] = {0, 0, 0};
    std::vector<int> points;
    for (int c : groups[best_name]) {
      const size_t o = static_cast<size_t>(c) * kk + k;
      if (!m.valid(o) || !std::isfinite(mu[o])) continue;
      u.cells.push_back(c);
      const double w = 1.0 / (m.noise(o) * m.noise(o)), r = m.y(o) - mu[o];
      const double dd = d.cells[c].distance_m;
      const double f[3] = {1.0, dd, dd * dd};
      for (int j = 0; j < 3; ++j) s[j] += w * f[j] * f[j], sr[j] += w * f[j] * r;
      sw += w, swr += w * r;
      chi2 += z[o] * z[o];
      max_d = std::max(max_d, dd);
      if (!pe.point.empty() &&
          std::find(points.begin(), points.end(), pe.point[c]) == points.end())
        points.push_back(pe.point[c]);
    }
    u.size = sw > 0 ? swr / sw : NAN;
    // Its standard error: the recordings of one test point share its placement scatter.
    {
      std::map<int, double> tau_sum;
      double var = 0, wsum = 0;
      for (int c : u.cells) {
        const size_t o = static_cast<size_t>(c) * kk + k;
        const double w = 1.0 / (m.noise(o) * m.noise(o));
        var += w * w * m.replicate_noise(o) * m.replicate_noise(o);
        tau_sum[pe.point.empty() ? -1 - c : pe.point[c]] += w * m.placement(o);
        wsum += w;
      }
      for (const auto& [t, v] : tau_sum) var += v * v;
      u.size_se = wsum > 0 ? std::sqrt(var) / wsum : NAN;
    }
    u.chi2 = chi2;
    u.df = static_cast<int>(u.cells.size());
    u.p_value = ChiSquareSurvival(chi2, u.df);
    u.share_pct = 100 * chi2 / total;
    const char* forms[3] = {"constant", "∝ D", "∝ D²"};
    int best = 0;
    double best_gain = -1;
    for (int j = 0; j < 3; ++j) {
      const double gain = s[j] > 0 ? sr[j] * sr[j] / s[j] : 0;  // Σw·r² explained
      if (gain > best_gain) best_gain = gain, best = j;
    }
    u.form = points.size() == 1 ? "one test point" : forms[best];
    const double coef = s[best] > 0 ? sr[best] / s[best] : 0;
    u.size_at_max = coef * (best == 0 ? 1.0 : best == 1 ? max_d : max_d * max_d);
    out.push_back(u);
  }
  std::sort(out.begin(), out.end(),
            [](const Unexplained& a, const Unexplained& b) { return a.chi2 > b.chi2; });
  return out;
}

}  // namespace depthbias::gap
