#include "gap/limits.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>

#include "gap/noise.h"

namespace depthbias::gap {
namespace {

// The node of an axis nearest a value (in the axis's coordinate).
int NearestNode(const Axis& axis, double value) {
  int best = 0;
  for (size_t i = 1; i < axis.nodes.size(); ++i)
    if (std::abs(Coordinate(axis, axis.nodes[i]) - Coordinate(axis, value)) <
        std::abs(Coordinate(axis, axis.nodes[best]) - Coordinate(axis, value)))
      best = static_cast<int>(i);
  return best;
}

// The whitened observations and calibration directions of the marked cells.
struct Whitened {
  GapModel::Whitening w;
  Eigen::MatrixXd n;  // [position in w.obs][2·scenario + component]

  // L⁻¹ v for v given in w.obs's order.
  Eigen::VectorXd Apply(const Eigen::VectorXd& v) const {
    Eigen::VectorXd z(v.size());
    for (size_t b = 0; b + 1 < w.starts.size(); ++b) {
      const int st = w.starts[b], len = w.starts[b + 1] - st;
      for (int r = 0; r < len; ++r) {
        double e = 0;
        for (int c = 0; c <= r; ++c) e += w.linv[b][r * len + c] * v[st + c];
        z[st + r] = e;
      }
    }
    return z;
  }
};

}  // namespace

DetectionLimits FindDetectionLimits(const GapModel& model, const std::vector<char>& cells,
                                    const LimitSettings& settings, const ModelFit* selection) {
  DetectionLimits out;
  out.settings = settings;
  const Design& d = model.design();
  const Simulations& sims = model.sims();
  const int k_count = model.num_metrics();
  const int scenarios = d.num_scenarios();

  std::vector<size_t> obs;
  for (int o = 0; o < model.num_obs(); ++o)
    if (model.valid(o) && cells[o / k_count]) obs.push_back(static_cast<size_t>(o));
  out.observations = static_cast<int>(obs.size());
  if (obs.size() < 2) return out;
  out.z_needed = std::sqrt(std::log(static_cast<double>(obs.size()))) +
                 TwoSidedCritical(2 * (1 - settings.power));
  for (int c = 0; c < d.num_cells(); ++c)
    if (cells[c]) out.far_distance_m = std::max(out.far_distance_m, d.cells[c].distance_m);

  Whitened wh;
  wh.w = model.Whiten(obs);
  const int n_obs = static_cast<int>(wh.w.obs.size());
  {
    Eigen::MatrixXd raw = Eigen::MatrixXd::Zero(n_obs, 2 * scenarios);
    for (int i = 0; i < n_obs; ++i) {
      const size_t o = wh.w.obs[i];
      const int s = d.scenario[o / k_count];
      raw(i, 2 * s) = sims.jac_log_sigma[o];
      raw(i, 2 * s + 1) = sims.jac_logit_p[o];
    }
    wh.n.resize(n_obs, 2 * scenarios);
    for (int j = 0; j < 2 * scenarios; ++j) wh.n.col(j) = wh.Apply(raw.col(j));
  }
  // The selected terms' whitened directions: for each term, group and continuous axis, the
  // departure's central difference in the axis's coordinate at the fitted values (one-sided at
  // the grid's ends), on the group's observations. by_term[j]: the column's term.
  // A group the selection did not fit (no cells) and a discrete axis (FitTerms holds it) give
  // none. selection_frozen: the calibration components the selection holds (GapModel::Frozen).
  Eigen::MatrixXd selected_n;
  std::vector<int> by_term;
  int selection_frozen = 0;
  if (selection) {
    std::vector<Eigen::VectorXd> columns;
    std::vector<Term> held;
    for (const TermFit& t : selection->terms) {
      held.push_back(t.term);
      const int c = t.term.candidate;
      const std::vector<Axis>& cand_axes = model.surface(c).candidate.axes;
      const int axes = static_cast<int>(cand_axes.size());
      for (int g = 0; g < model.NumGroups(t.term) && g < static_cast<int>(t.values.size()); ++g)
        for (int a = 0; a < axes && a < 2; ++a) {
          if (cand_axes[a].discrete || t.term.Discrete(g, a) >= 0 ||
              static_cast<int>(t.values[g].size()) < axes ||
              (g < static_cast<int>(t.group_used.size()) && !t.group_used[g]))
            continue;
          const std::vector<double>& nodes = model.NodeCoords(c, a);
          if (nodes.size() < 2) continue;
          double u[2] = {0, 0};
          for (int b = 0; b < axes && b < 2; ++b) u[b] = model.ToCoord(c, b, t.values[g][b]);
          if (!std::isfinite(u[a])) continue;
          const double h = 1e-3 * (nodes.back() - nodes.front());
          const double lo = std::max(nodes.front(), u[a] - h);
          const double hi = std::min(nodes.back(), u[a] + h);
          if (!(hi > lo)) continue;
          Eigen::VectorXd raw = Eigen::VectorXd::Zero(n_obs);
          for (int i = 0; i < n_obs; ++i) {
            const size_t o = wh.w.obs[i];
            if (model.Group(t.term, static_cast<int>(o / k_count)) != g) continue;
            double v[2] = {u[0], u[1]};
            v[a] = hi;
            const double up = model.Delta(t.term, v, o);
            v[a] = lo;
            raw[i] = (up - model.Delta(t.term, v, o)) / (hi - lo);
          }
          if (!(raw.squaredNorm() > 0)) continue;
          columns.push_back(wh.Apply(raw));
          by_term.push_back(c);
        }
    }
    selected_n.resize(n_obs, static_cast<int>(columns.size()));
    for (size_t j = 0; j < columns.size(); ++j) selected_n.col(static_cast<int>(j)) = columns[j];
    selection_frozen = model.Frozen(held);
  }

  // The median bias's index among the compared metrics, and the far cells' observations.
  int km = -1;
  for (int k = 0; k < k_count; ++k)
    if (d.metrics[k] == kMedianBias) km = k;
  std::vector<size_t> far;
  for (int c = 0; c < d.num_cells() && km >= 0; ++c) {
    const size_t o = static_cast<size_t>(c) * k_count + km;
    if (cells[c] && d.cells[c].distance_m == out.far_distance_m && model.valid(o))
      far.push_back(o);
  }

  const FitSettings& fs = model.settings();
  for (size_t i = 0; i < sims.surfaces.size(); ++i) {
    const int cand_index = static_cast<int>(i);
    const Candidate& cand = sims.surfaces[i].candidate;
    DetectionLimit lim;
    lim.effect = cand.effect;
    lim.frozen = model.Absorbs(cand_index);
    int on = -1;
    for (size_t a = 0; a < cand.axes.size(); ++a)
      if (on < 0 && std::isfinite(cand.axes[a].neutral)) on = static_cast<int>(a);
    if (on < 0) {
      out.effects.push_back(lim);
      continue;
    }
    const Axis& axis = cand.axes[on];
    lim.param = axis.param;
    lim.neutral = axis.neutral;
    lim.discrete = axis.discrete;
    Term term{cand_index, Scope::kShared, {std::vector<int>(cand.axes.size(), -1)}};
    double u[2] = {0, 0};
    const int held = cand.axes.size() > 1 ? 1 - on : -1;
    if (held >= 0) {
      const Axis& h = cand.axes[held];
      const int node = NearestNode(h, h.reference);
      if (h.discrete) term.discrete_node[0][held] = node;
      u[held] = Coordinate(h, h.nodes[node]);
      lim.other = h.param;
      lim.other_value = h.nodes[node];
    }

    // The calibration directions a fit holding this effect (and the selection) moves, and
    // their priors.
    std::vector<int> cols;
    std::vector<double> prec;
    for (int s = 0; s < scenarios; ++s)
      for (int comp = 0; comp < 2; ++comp) {
        if ((lim.frozen | selection_frozen) & (1 << comp)) continue;
        cols.push_back(2 * s + comp);
        prec.push_back(1 / std::pow(comp == 0 ? fs.tau_log_sigma : fs.tau_logit_p, 2));
      }
    // And the selected terms' but this effect's own, free (a trace of ridge keeps a direction
    // two groups share solvable).
    std::vector<int> beside;
    for (size_t j = 0; j < by_term.size(); ++j)
      if (by_term[j] != cand_index) beside.push_back(static_cast<int>(j));
    const int n_cols = static_cast<int>(cols.size() + beside.size());
    Eigen::MatrixXd n(n_obs, n_cols);
    for (size_t j = 0; j < cols.size(); ++j) n.col(j) = wh.n.col(cols[j]);
    for (size_t j = 0; j < beside.size(); ++j)
      n.col(static_cast<int>(cols.size() + j)) = selected_n.col(beside[j]);
    Eigen::MatrixXd a = n.transpose() * n;
    for (size_t j = 0; j < cols.size(); ++j) a(j, j) += prec[j];
    for (size_t j = cols.size(); j < static_cast<size_t>(n_cols); ++j) a(j, j) *= 1 + 1e-9;
    const Eigen::LDLT<Eigen::MatrixXd> solve(a);

    // Both bars' scores at a coordinate of the axis (each ≥ 0 where it passes), and the far
    // median's change there.
    struct Score {
      double test = 0, share = 0;
    };
    const double p = settings.min_share;
    const int folds = static_cast<int>(settings.fold_gap_sq.size());
    bool share_bar = folds > 0 && static_cast<int>(settings.fold.size()) == d.num_cells();
    for (const auto& g : settings.fold_gap_sq)
      share_bar = share_bar && static_cast<int>(g.size()) == k_count;
    auto score = [&](double coord, double* far_m) {
      u[on] = coord;
      Eigen::VectorXd delta(n_obs);
      // γ[f][k]: the gain in fold f's metric k, the effect's own movement there.
      std::vector<std::vector<double>> gamma(folds, std::vector<double>(k_count, 0.0));
      for (int j = 0; j < n_obs; ++j) {
        const size_t o = wh.w.obs[j];
        delta[j] = model.Delta(term, u, o);
        const int f = share_bar ? settings.fold[o / k_count] : -1;
        if (f >= 0 && f < folds) gamma[f][o % k_count] += std::pow(delta[j] / model.noise(o), 2);
      }
      const Eigen::VectorXd z = wh.Apply(delta);
      double lambda = z.squaredNorm();
      if (n_cols > 0) {
        const Eigen::VectorXd b = n.transpose() * z;
        lambda -= b.dot(solve.solve(b));
      }
      if (far_m) {
        double sum = 0;
        for (size_t o : far) sum += model.Delta(term, u, o);
        *far_m = far.empty() ? NAN : sum / static_cast<double>(far.size());
      }
      Score sc;
      sc.test = std::sqrt(std::max(lambda, 0.0)) - out.z_needed;
      if (share_bar) {
        // Read in the whole gap: γ_f / (G_f + γ_f) per fold, Σγ / Σ(G + γ) pooled; and in the
        // metrics the effect moves, each weighing by its movement γ_k (MovedShare):
        // Σ_k γ_k² / Σ_k γ_k (G_k + γ_k), per fold and pooled. Either reading keeps it.
        double own[2] = {0, 0};
        int counted = 0;
        std::vector<double> pooled_gain(k_count, 0.0), pooled_gap(k_count, 0.0);
        for (int f = 0; f < folds; ++f) {
          double num = 0, den = 0, gain = 0, gap = 0;
          for (int k = 0; k < k_count; ++k) {
            const double g = settings.fold_gap_sq[f][k], y = gamma[f][k];
            gain += y;
            gap += g;
            num += y * y;
            den += y * (g + y);
            pooled_gain[k] += y;
            pooled_gap[k] += g + y;
          }
          if (!(gap > 0)) continue;
          own[0] += gain / (gap + gain);
          own[1] += den > 0 ? num / den : 0;
          ++counted;
        }
        double gain = 0, whole = 0, num = 0, den = 0;
        for (int k = 0; k < k_count; ++k) {
          gain += pooled_gain[k];
          whole += pooled_gap[k];
          num += pooled_gain[k] * pooled_gain[k];
          den += pooled_gain[k] * pooled_gap[k];
        }
        const double pooled[2] = {whole > 0 ? gain / whole : 0, den > 0 ? num / den : 0};
        const double need_own[2] = {settings.min_own_share, settings.min_own_moved_share};
        const double need[2] = {p, settings.min_moved_share};
        sc.share = -std::numeric_limits<double>::infinity();
        for (int m = 0; m < 2; ++m) {
          double v = (counted ? own[m] / counted : 0) - need_own[m];
          if (settings.pooled) v = std::min(v, pooled[m] - need[m]);
          sc.share = std::max(sc.share, v);
        }
      }
      return sc;
    };

    const int n0 = NearestNode(axis, axis.neutral);
    const double c0 = Coordinate(axis, axis.neutral);
    for (int side = 0; side < 2; ++side) {
      // The coordinates walked from the neutral value: the nodes of a discrete axis, fine
      // steps of a continuous one.
      std::vector<double> walk;
      std::vector<int> walk_node;
      const int step = side == 0 ? -1 : 1;
      if (axis.discrete) {
        for (int node = n0 + step; node >= 0 && node < static_cast<int>(axis.nodes.size());
             node += step) {
          walk.push_back(Coordinate(axis, axis.nodes[node]));
          walk_node.push_back(node);
        }
      } else {
        const double end = Coordinate(axis, side == 0 ? axis.nodes.front() : axis.nodes.back());
        const int steps = 200;
        for (int i = 1; i <= steps && end != c0; ++i) walk.push_back(c0 + (end - c0) * i / steps);
      }
      lim.searched[side] = !walk.empty();
      double at[2] = {NAN, NAN};  // each bar's crossing
      double prev_c = c0;
      Score prev;
      prev.test = -out.z_needed;
      prev.share = share_bar ? -std::min(std::max(p, settings.min_own_share),
                                         std::max(settings.min_moved_share,
                                                  settings.min_own_moved_share))
                             : 0.0;
      for (size_t i = 0; i < walk.size() && !(std::isfinite(at[0]) && std::isfinite(at[1]));
           ++i) {
        if (axis.discrete) term.discrete_node[0][on] = walk_node[i];
        const Score sc = score(walk[i], nullptr);
        const double now[2] = {sc.test, sc.share}, before[2] = {prev.test, prev.share};
        for (int bar = 0; bar < 2; ++bar) {
          if (std::isfinite(at[bar]) || now[bar] < 0) continue;
          const double t = now[bar] == before[bar] ? 1 : -before[bar] / (now[bar] - before[bar]);
          at[bar] = axis.discrete ? walk[i] : prev_c + (walk[i] - prev_c) * t;
        }
        prev_c = walk[i];
        prev = sc;
      }
      auto value = [&](double coord) {
        return std::isfinite(coord) ? model.FromCoord(cand_index, on, coord) : NAN;
      };
      lim.by_test[side] = value(at[0]);
      if (share_bar) lim.by_share[side] = value(at[1]);
      const double binding = !share_bar ? at[0]
                             : std::isfinite(at[0]) && std::isfinite(at[1])
                                 ? (std::fabs(at[0] - c0) > std::fabs(at[1] - c0) ? at[0] : at[1])
                                 : NAN;
      lim.size[side] = value(binding);
      // Where no size passes, the far median at the grid's end: a camera at least that far off
      // could go unseen.
      const double far_at = std::isfinite(binding) ? binding : walk.empty() ? NAN : walk.back();
      if (std::isfinite(far_at)) {
        if (axis.discrete) term.discrete_node[0][on] = NearestNode(axis, value(far_at));
        score(far_at, &lim.far_m[side]);
      }
    }
    out.effects.push_back(lim);
  }
  return out;
}

void LimitsJson(records::JsonWriter& w, const DetectionLimits& l) {
  w.BeginObject("detection_limits");
  w.Number("power", l.settings.power).Number("z_needed", l.z_needed);
  w.Number("min_share", l.settings.min_share).Number("min_own_share", l.settings.min_own_share);
  w.Number("min_moved_share", l.settings.min_moved_share);
  w.Number("min_own_moved_share", l.settings.min_own_moved_share);
  w.Bool("pooled", l.settings.pooled).BeginArray("fold_gap_sq");  // [fold][metric]
  for (const auto& f : l.settings.fold_gap_sq) {
    w.BeginArray();
    for (double g : f) w.Number(g);
    w.EndArray();
  }
  w.EndArray();
  w.Integer("observations", l.observations).Number("far_distance_m", l.far_distance_m);
  w.BeginArray("effects");
  for (const DetectionLimit& e : l.effects) {
    w.BeginObject().String("effect", e.effect).String("param", e.param);
    w.Number("neutral", e.neutral).Bool("discrete", e.discrete);
    w.Bool("one_of_calibration", e.frozen != 0);
    if (!e.other.empty()) w.BeginObject("held").Number(e.other, e.other_value).EndObject();
    // Per side: null beyond the grid; absent where the grid does not extend that way.
    const char* side_name[2] = {"below", "above"};
    for (int side = 0; side < 2; ++side) {
      if (!e.searched[side]) continue;
      w.BeginObject(side_name[side]).Number("size", e.size[side]);
      w.Number("by_test", e.by_test[side]).Number("by_share", e.by_share[side]);
      w.Number("far_m", e.far_m[side]).EndObject();
    }
    w.EndObject();
  }
  w.EndArray().EndObject();
}

}  // namespace depthbias::gap
