// The fits of single candidates (from their grid profile) and cross-validation (fit.h).
#include "gap/fit.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Dense>

namespace depthbias::gap {
namespace {

// The node of a (possibly 2-D) grid as axis indices.
std::vector<int> NodeAxes(const Surface& s, int node) {
  if (s.candidate.axes.size() == 1) return {node};
  const int n1 = static_cast<int>(s.candidate.axes[1].nodes.size());
  return {node / n1, node % n1};
}

// Per scenario, the calibration moves that minimize Σ (r − a·n)² + Σ (n/τ)² given residuals r
// and the Jacobian columns a (plain squares), and the value reached.
struct ScenarioProfile {
  std::vector<std::array<double, 5>> normal;  // per scenario: Σa_σ², Σa_σa_p, Σa_p², Σa_σ r, Σa_p r
  std::vector<double> rr;                     // per scenario: Σ r²
};

double ProfiledValue(const ScenarioProfile& p, int s, const FitSettings& fs, int frozen) {
  const auto& n = p.normal[s];
  Eigen::Matrix2d a;
  const double held = 1e12;  // a frozen component: its move costs everything
  a << n[0] + (frozen & 1 ? held : 1 / (fs.tau_log_sigma * fs.tau_log_sigma)), n[1], n[1],
      n[2] + (frozen & 2 ? held : 1 / (fs.tau_logit_p * fs.tau_logit_p));
  const Eigen::Vector2d b(n[3], n[4]);
  const Eigen::Vector2d x = a.ldlt().solve(b);
  return p.rr[s] - b.dot(x);  // min of rᵀr − 2bᵀx + xᵀAx
}

// The deviance by which a discrete axis's node is chosen: Tukey's biweight at kWidthC noise
// units over the whitened residuals of the marked cells (a miss beyond weighs kWidthC²/3 whatever
// its size), plus the calibration's prior. Under placement scatter a window metric can sit in
// one of two modes: the median of a region whose background holds about half its valid samples
// jumps to the background as the outline falls on the pixel grid at another phase (region_spill
// at 4 px, sunset, HA, 12 m: 7.7 to 9.5 m far at 14 of 27 placements within ±4 % at 0°, 10° and
// 20°, docs/gap/cases.md). A loss that keeps growing with the miss lets the one test point in
// the other mode choose the width against all the others; the continuous parameters, smooth in
// placement, keep the fit's loss.
constexpr double kWidthC = 4.5;

double WidthDeviance(const GapModel& model, const ModelFit& fit, const std::vector<char>& cells,
                     bool with_prior = true) {
  const std::vector<double> mu = model.Predict(fit);
  const int k_count = model.num_metrics();
  std::vector<size_t> obs;
  for (size_t o = 0; o < mu.size(); ++o)
    if (model.valid(o) && cells[o / k_count] && std::isfinite(mu[o])) obs.push_back(o);
  const GapModel::Whitening w = model.Whiten(obs);
  double sum = with_prior ? fit.prior : 0.0;
  for (size_t b = 0; b + 1 < w.starts.size(); ++b) {
    const int st = w.starts[b], n = w.starts[b + 1] - st;
    for (int r = 0; r < n; ++r) {
      double e = 0;
      for (int c = 0; c <= r; ++c)
        e += w.linv[b][r * n + c] * (model.y(w.obs[st + c]) - mu[w.obs[st + c]]);
      const double x = e * e / (kWidthC * kWidthC);
      sum += x >= 1 ? kWidthC * kWidthC / 3 : e * e * (1 - x + x * x / 3);
    }
  }
  return sum;
}

}  // namespace

ModelFit FitCandidate(const GapModel& model, int candidate, Scope scope,
                      const std::vector<char>& train, const ModelFit* shared) {
  const Design& d = model.design();
  const Surface& surf = model.surface(candidate);
  const Candidate& cand = surf.candidate;
  const Simulations& sims = model.sims();
  const int k_count = model.num_metrics();
  const int scenarios = d.num_scenarios();
  const FitSettings& fs = model.settings();
  const int frozen = model.Absorbs(candidate);

  // Profiled value of every node, per scenario (plain squares, calibration in closed form).
  std::vector<std::vector<double>> value(surf.num_nodes, std::vector<double>(scenarios, 0.0));
  for (int node = 0; node < surf.num_nodes; ++node) {
    ScenarioProfile p;
    p.normal.assign(scenarios, {0, 0, 0, 0, 0});
    p.rr.assign(scenarios, 0.0);
    for (int c = 0; c < d.num_cells(); ++c) {
      if (!train[c]) continue;
      const int s = d.scenario[c];
      for (int k = 0; k < k_count; ++k) {
        const size_t o = static_cast<size_t>(c) * k_count + k;
        if (!model.valid(o)) continue;
        const double w = model.weight(o);
        const double r = (model.y(o) - surf.table[o * surf.num_nodes + node]) * w;
        const double as = sims.jac_log_sigma[o] * w, ap = sims.jac_logit_p[o] * w;
        auto& n = p.normal[s];
        n[0] += as * as;
        n[1] += as * ap;
        n[2] += ap * ap;
        n[3] += as * r;
        n[4] += ap * r;
        p.rr[s] += r * r;
      }
    }
    for (int s = 0; s < scenarios; ++s) value[node][s] = ProfiledValue(p, s, fs, frozen);
  }

  // Starting points. Shared: every local minimum of the profile over the grid (neighbours along
  // the continuous axes; an effect whose spreads are even in its sign has one on either side;
  // the absent effect once), the three lowest. Per light or scenario: each group's best node
  // (discrete axes included), and the shared fit's values.
  std::vector<int> discrete_axes;
  for (size_t a = 0; a < cand.axes.size(); ++a)
    if (cand.axes[a].discrete) discrete_axes.push_back(static_cast<int>(a));
  const int groups = ScopeGroups(d, scope);
  // Each group's profile: the sum over its scenarios.
  std::vector<std::vector<double>> group_value(surf.num_nodes, std::vector<double>(groups, 0.0));
  for (int node = 0; node < surf.num_nodes; ++node)
    for (int sc = 0; sc < scenarios; ++sc)
      group_value[node][ScopeGroupOf(d, scope, sc)] += value[node][sc];
  struct Option {
    std::vector<std::vector<int>> discrete_node;  // [group][axis]
    double value = 0;
    std::vector<std::vector<double>> values;  // [group][axis]
  };
  auto node_values = [&](int node) {
    const std::vector<int> ax = NodeAxes(surf, node);
    std::vector<double> v;
    for (size_t a = 0; a < cand.axes.size(); ++a) v.push_back(cand.axes[a].nodes[ax[a]]);
    return v;
  };
  auto discrete_of = [&](int node) {
    std::vector<int> d(cand.axes.size(), -1);
    const std::vector<int> ax = NodeAxes(surf, node);
    for (int a : discrete_axes) d[a] = ax[a];
    return d;
  };
  std::vector<Option> options;
  if (scope == Scope::kShared) {
    std::vector<double> total(surf.num_nodes, 0.0);
    for (int node = 0; node < surf.num_nodes; ++node)
      for (int sc = 0; sc < scenarios; ++sc) total[node] += value[node][sc];
    const int n1 = cand.axes.size() > 1 ? static_cast<int>(cand.axes[1].nodes.size()) : 1;
    for (int node = 0; node < surf.num_nodes; ++node) {
      const std::vector<int> ax = NodeAxes(surf, node);
      bool local = !IsNeutral(cand, node_values(node)) || node == 0 || discrete_axes.empty();
      for (size_t a = 0; a < cand.axes.size() && local; ++a) {
        if (cand.axes[a].discrete) continue;
        const int stride = a == 0 ? n1 : 1;
        if (ax[a] > 0 && total[node - stride] < total[node]) local = false;
        if (ax[a] + 1 < static_cast<int>(cand.axes[a].nodes.size()) &&
            total[node + stride] < total[node])
          local = false;
      }
      if (local) options.push_back({{discrete_of(node)}, total[node], {node_values(node)}});
    }
    std::sort(options.begin(), options.end(),
              [](const Option& a, const Option& b) { return a.value < b.value; });
    if (options.size() > 3) options.resize(3);
  } else {
    Option opt;
    for (int g = 0; g < groups; ++g) {
      int best_node = 0;
      for (int node = 1; node < surf.num_nodes; ++node)
        if (group_value[node][g] < group_value[best_node][g]) best_node = node;
      opt.value += group_value[best_node][g];
      opt.discrete_node.push_back(discrete_of(best_node));
      opt.values.push_back(node_values(best_node));
    }
    options.push_back(opt);
    if (shared && shared->success && !shared->terms.empty()) {
      const TermFit& t = shared->terms[0];
      options.push_back({std::vector<std::vector<int>>(groups, t.term.discrete_node[0]), 0,
                         std::vector<std::vector<double>>(groups, t.values[0])});
    }
  }

  // With a discrete axis, also each group's best node at every node of the discrete axes, so
  // that every width is tried (chosen by WidthDeviance below; per group, each group's width on
  // its own cells).
  std::vector<std::vector<int>> widths;
  for (int node = 0; node < surf.num_nodes && !discrete_axes.empty(); ++node)
    if (std::find(widths.begin(), widths.end(), discrete_of(node)) == widths.end())
      widths.push_back(discrete_of(node));
  for (const std::vector<int>& width : widths) {
    Option at;
    for (int g = 0; g < groups; ++g) {
      int best_node = -1;
      for (int node = 0; node < surf.num_nodes; ++node)
        if (discrete_of(node) == width &&
            (best_node < 0 || group_value[node][g] < group_value[best_node][g]))
          best_node = node;
      at.discrete_node.push_back(width);
      at.values.push_back(node_values(best_node));
    }
    // A width whose best node is already a start (a local minimum of the profile) is fitted once.
    if (std::none_of(options.begin(), options.end(), [&](const Option& o) {
          return o.discrete_node == at.discrete_node && o.values == at.values;
        }))
      options.push_back(at);
  }

  auto value_of = [&](const ModelFit& f) {
    return discrete_axes.empty() ? f.Deviance() : WidthDeviance(model, f, train);
  };
  auto fit_from = [&](const Option& opt) {
    ModelFit start;
    start.terms.emplace_back();
    start.terms[0].term = Term{candidate, scope, opt.discrete_node};
    start.terms[0].values = opt.values;
    return FitTerms(model, {start.terms[0].term}, train, &start);
  };
  std::vector<ModelFit> fits;  // the successful fits, in the options' order
  size_t lowest_fit = 0;
  double best_value = INFINITY;
  for (const Option& opt : options) {
    ModelFit f = fit_from(opt);
    if (!f.success) continue;
    const double v = value_of(f);
    if (fits.empty() || v < best_value) lowest_fit = fits.size(), best_value = v;
    fits.push_back(std::move(f));
  }
  ModelFit best = fits.empty() ? ModelFit() : fits[lowest_fit];
  // Per group, each group's widths and values from the fit whose WidthDeviance on the group's
  // cells is lowest (the calibration's prior, over every group, left out there and counted in the
  // refit's own WidthDeviance); refitted together.
  if (scope != Scope::kShared && !discrete_axes.empty() && fits.size() > 1) {
    Option mixed;
    for (int g = 0; g < groups; ++g) {
      std::vector<char> cells(d.num_cells(), 0);
      for (int c = 0; c < d.num_cells(); ++c)
        cells[c] = train[c] && ScopeGroupOf(d, scope, d.scenario[c]) == g;
      size_t pick = 0;
      double lowest = INFINITY;
      for (size_t i = 0; i < fits.size(); ++i) {
        const double v = WidthDeviance(model, fits[i], cells, false);
        if (v < lowest) lowest = v, pick = i;
      }
      const TermFit& t = fits[pick].terms[0];
      const size_t row = t.term.discrete_node.size() == 1 ? 0 : g;
      mixed.discrete_node.push_back(t.term.discrete_node[row]);
      mixed.values.push_back(t.values[t.values.size() == 1 ? 0 : g]);
    }
    ModelFit f = fit_from(mixed);
    if (f.success && value_of(f) < best_value) best = std::move(f);
  }
  if (!best.success && best.message.empty()) best.message = "no fit of " + cand.effect;
  return best;
}

void ProfileDiscreteAxes(const GapModel& model, const std::vector<char>& cells,
                         ModelFit* fit) {  // fit.h
  constexpr double kChi2_95 = 3.841459;
  std::vector<Term> terms;
  bool any = false;
  for (const TermFit& t : fit->terms) {
    terms.push_back(t.term);
    for (const Axis& a : model.surface(t.term.candidate).candidate.axes) any = any || a.discrete;
  }
  if (!any) return;
  auto refit = [&](const std::vector<Term>& with) {
    double best = INFINITY;
    for (const ModelFit* start : {static_cast<const ModelFit*>(fit),
                                  static_cast<const ModelFit*>(nullptr)}) {
      const ModelFit f = FitTerms(model, with, cells, start);
      if (f.success) best = std::min(best, f.Deviance());
    }
    return best;
  };
  const double at_fitted = refit(terms);
  if (!std::isfinite(at_fitted)) return;
  for (size_t i = 0; i < terms.size(); ++i) {
    TermFit& tf = fit->terms[i];
    const Candidate& cand = model.surface(tf.term.candidate).candidate;
    for (size_t a = 0; a < cand.axes.size(); ++a) {
      if (!cand.axes[a].discrete) continue;
      const std::vector<double>& nodes = cand.axes[a].nodes;
      for (size_t g = 0; g < tf.values.size(); ++g) {
        const int fitted = tf.term.Discrete(static_cast<int>(g), static_cast<int>(a));
        if (fitted < 0) continue;
        if (g < tf.group_used.size() && !tf.group_used[g]) {  // no cells: no interval
          tf.ci_lo[g][a] = tf.ci_hi[g][a] = NAN;
          continue;
        }
        // Every width's deviance; the interval is read from the lowest (the width fitted
        // alone, beside the others' widths, need not be the lowest here).
        std::vector<double> deviance(nodes.size(), INFINITY);
        deviance[fitted] = at_fitted;
        for (int j = 0; j < static_cast<int>(nodes.size()); ++j) {
          if (j == fitted) continue;
          std::vector<Term> moved = terms;
          Term& m = moved[i];
          if (m.discrete_node.size() == 1 && tf.values.size() > 1)
            m.discrete_node.assign(tf.values.size(), m.discrete_node[0]);
          m.discrete_node[m.discrete_node.size() == 1 ? 0 : g][a] = j;
          deviance[j] = refit(moved);
        }
        const double lowest = *std::min_element(deviance.begin(), deviance.end());
        double lo = nodes[fitted], hi = nodes[fitted];
        for (size_t j = 0; j < nodes.size(); ++j)
          if (deviance[j] - lowest <= kChi2_95)
            lo = std::min(lo, nodes[j]), hi = std::max(hi, nodes[j]);
        tf.ci_lo[g][a] = lo;
        tf.ci_hi[g][a] = hi;
        tf.profiled = true;
      }
    }
  }
}

HeldOut CrossValidate(const GapModel& model, const std::vector<Term>& terms,
                      const std::vector<int>& fold, int num_folds, const ModelFit& full,
                      const std::vector<char>& use) {
  HeldOut out;
  const Design& d = model.design();
  const int k_count = model.num_metrics();
  out.mu.assign(model.num_obs(), NAN);
  out.cells.assign(d.num_cells(), 0);
  for (int f = 0; f < num_folds; ++f) {
    std::vector<char> train(d.num_cells(), 0), held(d.num_cells(), 0);
    bool any = false;
    for (int c = 0; c < d.num_cells(); ++c) {
      const bool in = use.empty() || use[c];
      train[c] = in && fold[c] != f;
      held[c] = in && fold[c] == f;
      any = any || held[c];
    }
    if (!any) continue;
    ModelFit fit;
    if (terms.empty()) {
      fit = FitTerms(model, {}, train);
    } else if (terms.size() == 1) {
      const ModelFit shared = terms[0].scope != Scope::kShared
                                  ? FitCandidate(model, terms[0].candidate, Scope::kShared, train)
                                  : ModelFit();
      fit = FitCandidate(model, terms[0].candidate, terms[0].scope, train, &shared);
    } else {
      fit = FitTerms(model, terms, train, &full);
    }
    if (!fit.success) {
      out.success = false;
      out.message = "fold " + std::to_string(f + 1) + ": " + fit.message;
      return out;
    }
    const std::vector<double> mu = model.Predict(fit);
    for (int c = 0; c < d.num_cells(); ++c) {
      if (!held[c]) continue;
      out.cells[c] = 1;
      for (int k = 0; k < k_count; ++k) {
        const size_t o = static_cast<size_t>(c) * k_count + k;
        out.mu[o] = mu[o];
      }
    }
  }
  out.data_deviance = model.DataDeviance(out.mu, out.cells);
  return out;
}

ModelFit FitBeside(const GapModel& model, const ModelFit& fit, const TermFit& beside,
                   const std::vector<char>& train) {
  ModelFit start = fit;
  start.terms.push_back(beside);
  std::vector<Term> terms;
  for (const TermFit& t : start.terms) terms.push_back(t.term);
  return FitTerms(model, terms, train, &start);
}

}  // namespace depthbias::gap
