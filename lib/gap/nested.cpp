#include "gap/nested.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

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

Nested RunNested(const Design& d, const Simulations& sims, const sim::SimParams& base,
                 const DiagnoseParams& params, const std::vector<int>& fold, int num_folds,
                 const GapModel& full) {
  Nested n;
  const int kk = d.num_metrics();
  const size_t obs = d.real.size();
  n.cells.assign(d.num_cells(), 0);
  for (auto* z : {&n.z_baseline, &n.z_calibrated, &n.z_selected, &n.z_simulated})
    z->assign(obs, NAN);
  bool all_simulated = true;
  for (int f = 0; f < num_folds; ++f) {
    std::vector<char> train(d.num_cells(), 0), held(d.num_cells(), 0);
    NestedFold nf;
    for (int c = 0; c < d.num_cells(); ++c) {
      train[c] = fold[c] != f;
      held[c] = fold[c] == f;
      if (held[c] && nf.held.empty()) nf.held = LevelOf(d.cells[c], 0);
      nf.cells += held[c];
    }
    if (nf.cells == 0) continue;
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
      nf.deviance_calibrated = model.DataDeviance(mu0, held);
      nf.deviance_selected = model.DataDeviance(mu1, held);
      n.gain += nf.deviance_calibrated - nf.deviance_selected;
      const std::vector<double> zb = Scaled(model, sims.base), z0 = Scaled(model, mu0),
                                z1 = Scaled(model, mu1);
      std::vector<double> zs(obs, NAN);
      try {
        const Design sub = Subset(d, held);
        const std::vector<double> v = SimulateValues(
            SelectedParams(sims, base, sel.current, d.num_scenarios()), sub, params.simulate);
        std::vector<double> mu(obs, NAN);
        int i = 0;
        for (int c = 0; c < d.num_cells(); ++c) {
          if (!held[c]) continue;
          for (int k = 0; k < kk; ++k)
            mu[static_cast<size_t>(c) * kk + k] = v[static_cast<size_t>(i) * kk + k];
          ++i;
        }
        zs = Scaled(model, mu);
        nf.simulated = true;
      } catch (const std::exception& e) {
        all_simulated = false;
        n.message = "fold " + nf.held + ": not simulated: " + e.what();
      }
      for (int c = 0; c < d.num_cells(); ++c) {
        if (!held[c]) continue;
        n.cells[c] = 1;
        for (int k = 0; k < kk; ++k) {
          const size_t o = static_cast<size_t>(c) * kk + k;
          n.z_baseline[o] = zb[o];
          n.z_calibrated[o] = z0[o];
          n.z_selected[o] = z1[o];
          n.z_simulated[o] = zs[o];
        }
      }
    } catch (const std::exception& e) {
      n.message = "fold " + nf.held + ": " + e.what();
      return n;
    }
    n.folds.push_back(nf);
  }
  n.baseline = Stat(full, n.z_baseline, n.cells);
  n.calibrated = Stat(full, n.z_calibrated, n.cells);
  n.selected = Stat(full, n.z_selected, n.cells);
  n.shrink_heldout_nested_pct = Shrink(n.baseline, n.selected);
  if (all_simulated) {
    n.simulated = Stat(full, n.z_simulated, n.cells);
    n.shrink_simulated_pct = Shrink(n.baseline, n.simulated);
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
