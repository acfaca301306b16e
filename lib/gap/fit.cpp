#include "gap/fit.h"
#include "gap/robust_covariance.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>

#include <Eigen/Dense>
#include <ceres/ceres.h>

namespace depthbias::gap {
namespace {

// simulations.cpp's Pchip in parts, with the same arithmetic and its slopes (PchipSlope): where
// t falls among the nodes and its Hermite weights (a Stencil, the same for every curve on those
// nodes), and a curve's value from them (Interpolate).
struct Stencil {
  int node = 0;  // ≥ 0: the value is y[node] (t at or beyond an end); −1: interval i
  int i = 0;
  double h = 0;
  double w[4] = {0, 0, 0, 0};  // weights of y[i], m[i]·h, y[i + 1], m[i + 1]·h
};

Stencil StencilAt(const double* x, int n, double t) {
  Stencil st;
  if (n == 1 || t <= x[0]) return st;
  if (t >= x[n - 1]) {
    st.node = n - 1;
    return st;
  }
  int i = static_cast<int>(std::upper_bound(x, x + n, t) - x) - 1;
  i = std::clamp(i, 0, n - 2);
  const double h = x[i + 1] - x[i], s = (t - x[i]) / h;
  const double s2 = s * s, s3 = s2 * s;
  st.node = -1;
  st.i = i;
  st.h = h;
  st.w[0] = 2 * s3 - 3 * s2 + 1;
  st.w[1] = s3 - 2 * s2 + s;
  st.w[2] = -2 * s3 + 3 * s2;
  st.w[3] = s3 - s2;
  return st;
}

double Interpolate(const Stencil& st, const double* y, const double* m) {
  if (st.node >= 0) return y[st.node];
  const int i = st.i;
  const double m0 = m[i] * st.h, m1 = m[i + 1] * st.h;
  return st.w[0] * y[i] + st.w[1] * m0 + st.w[2] * y[i + 1] + st.w[3] * m1;
}

// Where the continuous coordinates of a fit live: one block per (term, used group), one per
// fitted scenario's calibration.
struct Layout {
  struct Block {
    int term = -1, group = -1, scenario = -1;
    std::vector<int> axes;  // continuous axes of the term (term blocks)
  };
  std::vector<Block> blocks;
  std::vector<std::vector<int>> term_block;  // [term][group] → block, −1 if the group is unused
  std::vector<int> scenario_block;           // [scenario] → block, −1 if no cell is fitted
};

class GapCost : public ceres::CostFunction {
 public:
  GapCost(const GapModel& model, const std::vector<Term>& terms, const Layout& layout,
          GapModel::Whitening white, std::vector<std::vector<std::vector<double>>> fixed)
      : model_(model), terms_(terms), layout_(layout), white_(std::move(white)),
        obs_(white_.obs), fixed_(std::move(fixed)), shares_(model.SharesWindow(terms)) {
    for (const auto& b : layout_.blocks)
      mutable_parameter_block_sizes()->push_back(b.term >= 0 ? static_cast<int>(b.axes.size())
                                                             : 2);
    int priors = 0;
    for (int b : layout_.scenario_block) priors += b >= 0 ? 2 : 0;
    set_num_residuals(static_cast<int>(obs_.size()) + priors);
    PrepareCurves();
    PrepareCalibration();
  }

  const std::vector<size_t>& obs() const { return obs_; }  // the data rows' observations
  // Whitening block w (L⁻¹ lower triangular) applied to one column (rows `stride` apart).
  void Whiten(size_t w, double* col, size_t stride, double* tmp) const {
    const int st = white_.starts[w], n = white_.starts[w + 1] - st;
    const double* l = white_.linv[w].data();
    for (int r = 0; r < n; ++r) {
      double sum = 0;
      for (int c = 0; c <= r; ++c) sum += l[r * n + c] * col[(st + c) * stride];
      tmp[r] = sum;
    }
    for (int r = 0; r < n; ++r) col[(st + r) * stride] = tmp[r];
  }

  // The calibration blocks' Jacobian, −J of their scenario's observations whitened, does not
  // depend on the parameters: made once, copied at each evaluation before Huber's scaling.
  void PrepareCalibration() {
    const Simulations& s = model_.sims();
    calibration_.assign(layout_.blocks.size(), {});
    for (int nb : layout_.scenario_block)
      if (nb >= 0) calibration_[nb].assign(static_cast<size_t>(num_residuals()) * 2, 0.0);
    for (size_t i = 0; i < obs_.size(); ++i) {
      const size_t o = obs_[i];
      const int nb = scenario_block_[i];
      if (nb < 0) continue;
      calibration_[nb][i * 2] = -s.jac_log_sigma[o];
      calibration_[nb][i * 2 + 1] = -s.jac_logit_p[o];
    }
    std::vector<double> tmp(obs_.size());
    for (size_t w = 0; w + 1 < white_.starts.size(); ++w)
      for (auto& column : calibration_)
        if (!column.empty())
          for (int j = 0; j < 2; ++j) Whiten(w, column.data() + j, 2, tmp.data());
  }

  // The curve GapModel::Delta interpolates for term t at observation obs_[i], with its slopes
  // computed once for all the solver's evaluations: the term's one axis, or its second axis
  // along the row of a discrete first one (the term's nodes x_[t], n_[t], along axis_[t]).
  // Other terms (two continuous axes) go to GapModel::Delta (n_[t] = 0 or y = nullptr).
  struct Curve {
    const double* y = nullptr;  // the row of the surface's table
    size_t slopes = 0;          // offset in slopes_
  };
  void PrepareCurves() {
    const int k_count = model_.num_metrics();
    curves_.assign(terms_.size(), {});
    x_.assign(terms_.size(), nullptr);
    n_.assign(terms_.size(), 0);
    axis_.assign(terms_.size(), 0);
    stencil_offset_.assign(terms_.size() + 1, 0);
    group_.assign(terms_.size(), {});
    step_.assign(terms_.size(), {0, 0});
    scenario_block_.resize(obs_.size());
    for (size_t i = 0; i < obs_.size(); ++i)
      scenario_block_[i] =
          layout_.scenario_block[model_.design().scenario[obs_[i] / k_count]];
    for (size_t t = 0; t < terms_.size(); ++t) {
      const Term& term = terms_[t];
      const Surface& surf = model_.surface(term.candidate);
      const size_t axes = surf.candidate.axes.size();
      stencil_offset_[t + 1] = stencil_offset_[t] + model_.NumGroups(term);
      for (size_t a = 0; a < axes; ++a) {
        const auto& nodes = model_.NodeCoords(term.candidate, static_cast<int>(a));
        step_[t][a] = 1e-3 * (nodes.back() - nodes.front());
      }
      group_[t].resize(obs_.size());
      for (size_t i = 0; i < obs_.size(); ++i)
        group_[t][i] = model_.Group(term, static_cast<int>(obs_[i] / k_count));
      axis_[t] = axes == 1 ? 0 : 1;
      const auto& x = model_.NodeCoords(term.candidate, axis_[t]);
      x_[t] = x.data();
      n_[t] = static_cast<int>(x.size());
      curves_[t].resize(obs_.size());
      for (size_t i = 0; i < obs_.size(); ++i) {
        const size_t o = obs_[i];
        const double* row = &surf.table[o * surf.num_nodes];
        Curve& c = curves_[t][i];
        if (axes == 1) {
          c.y = row;
        } else {
          const int d0 = term.Discrete(model_.Group(term, static_cast<int>(o / k_count)), 0);
          if (d0 < 0) continue;  // no curve: Delta
          c.y = row + static_cast<size_t>(d0) * n_[t];
        }
        c.slopes = slopes_.size();
        for (int j = 0; j < n_[t]; ++j)
          slopes_.push_back(n_[t] > 1 ? PchipSlope(x_[t], c.y, n_[t], j) : 0.0);
      }
    }
  }

  // A term's group at the parameters: its coordinates, and its stencils at them and a step
  // either side along its interpolated axis (the Jacobian's central differences).
  struct At {
    double u[2] = {0, 0};
    Stencil st[3];
  };
  std::vector<At> Coordinates(double const* const* p) const {
    std::vector<At> out(stencil_offset_.back());
    for (size_t t = 0; t < terms_.size(); ++t) {
      const int ax = axis_[t];
      const double h = step_[t][ax];
      for (int g = 0; g < stencil_offset_[t + 1] - stencil_offset_[t]; ++g) {
        At& a = out[stencil_offset_[t] + g];
        TermCoords(p, static_cast<int>(t), g, a.u);
        a.st[0] = StencilAt(x_[t], n_[t], a.u[ax]);
        a.st[1] = StencilAt(x_[t], n_[t], a.u[ax] + h);
        a.st[2] = StencilAt(x_[t], n_[t], a.u[ax] - h);
      }
    }
    return out;
  }

  // GapModel::Delta of term t at observation obs_[i]: from stencil k (curves), else at the
  // coordinates u.
  double Delta(const Stencil& st, size_t t, const double* u, size_t i) const {
    const Curve& c = curves_[t][i];
    const size_t o = obs_[i];
    if (!c.y) return model_.Delta(terms_[t], u, o);
    return Interpolate(st, c.y, &slopes_[c.slopes]) - model_.sims().base[o];
  }

  // Coordinates of every axis of term t's group g at the current parameters.
  void TermCoords(double const* const* p, int t, int g, double* u) const {
    const std::vector<double>& fixed = fixed_[t][g];
    for (size_t a = 0; a < fixed.size(); ++a) u[a] = fixed[a];
    const int b = layout_.term_block[t][g];
    if (b < 0) return;
    const auto& axes = layout_.blocks[b].axes;
    for (size_t j = 0; j < axes.size(); ++j) u[axes[j]] = p[b][j];
  }

  bool Evaluate(double const* const* p, double* residuals, double** jac) const override {
    const double huber = model_.settings().huber_k;
    const Simulations& s = model_.sims();
    const size_t nb_count = layout_.blocks.size();
    if (jac) {
      for (size_t b = 0; b < nb_count; ++b) {
        if (!jac[b]) continue;
        if (!calibration_[b].empty())
          std::copy(calibration_[b].begin(), calibration_[b].end(), jac[b]);
        else
          std::fill(jac[b], jac[b] + num_residuals() * parameter_block_sizes()[b], 0.0);
      }
    }
    // Raw residuals y − μ and their derivatives −∂μ/∂p.
    const std::vector<At> at = Coordinates(p);
    double v[2];
    std::vector<const double*> ut(terms_.size());  // (1a)'s coordinates, term by term
    for (size_t i = 0; i < obs_.size(); ++i) {
      const size_t o = obs_[i];
      double mu = s.base[o];
      for (size_t t = 0; t < terms_.size(); ++t) {
        const At& a = at[stencil_offset_[t] + group_[t][i]];
        mu += Delta(a.st[0], t, a.u, i);
        ut[t] = a.u;
      }
      if (shares_) mu += model_.WindowInteraction(terms_, ut.data(), o);
      const int nb = scenario_block_[i];
      if (nb >= 0) mu += s.jac_log_sigma[o] * p[nb][0] + s.jac_logit_p[o] * p[nb][1];
      residuals[i] = model_.y(o) - mu;
      if (!jac) continue;
      for (size_t t = 0; t < terms_.size(); ++t) {
        const int grp = group_[t][i];
        const int b = layout_.term_block[t][grp];
        if (b < 0 || !jac[b]) continue;
        const auto& axes = layout_.blocks[b].axes;
        const At& a = at[stencil_offset_[t] + grp];
        for (size_t j = 0; j < axes.size(); ++j) {
          const double h = step_[t][axes[j]];
          const bool along = axes[j] == axis_[t];  // the stencils' steps
          std::copy(a.u, a.u + 2, v);
          v[axes[j]] = a.u[axes[j]] + h;
          const double up = along ? Delta(a.st[1], t, v, i) : model_.Delta(terms_[t], v, o);
          v[axes[j]] = a.u[axes[j]] - h;
          double down = along ? Delta(a.st[2], t, v, i) : model_.Delta(terms_[t], v, o);
          if (shares_) {  // (1a) at the same steps: down − up of it
            ut[t] = v;
            down += model_.WindowInteraction(terms_, ut.data(), o);
            v[axes[j]] = a.u[axes[j]] + h;
            down -= model_.WindowInteraction(terms_, ut.data(), o);
            ut[t] = a.u;
          }
          jac[b][i * axes.size() + j] = -(up - down) / (2 * h);
        }
      }
    }
    // Whitened block by block (the calibration blocks are already), then Huber's loss row by
    // row.
    std::vector<double> tmp(obs_.size());
    for (size_t w = 0; w + 1 < white_.starts.size(); ++w) {
      Whiten(w, residuals, 1, tmp.data());
      if (!jac) continue;
      for (size_t b = 0; b < nb_count; ++b) {
        if (!jac[b] || !calibration_[b].empty()) continue;
        const int size = parameter_block_sizes()[b];
        for (int j = 0; j < size; ++j) Whiten(w, jac[b] + j, size, tmp.data());
      }
    }
    for (size_t i = 0; i < obs_.size(); ++i) {
      double d = 1;
      residuals[i] = Robust(residuals[i], huber, &d);
      if (!jac || d == 1) continue;
      for (size_t b = 0; b < nb_count; ++b) {
        if (!jac[b]) continue;
        const int size = parameter_block_sizes()[b];
        for (int j = 0; j < size; ++j) jac[b][i * size + j] *= d;
      }
    }
    size_t row = obs_.size();
    const double tau[2] = {model_.settings().tau_log_sigma, model_.settings().tau_logit_p};
    for (size_t sc = 0; sc < layout_.scenario_block.size(); ++sc) {
      const int nb = layout_.scenario_block[sc];
      if (nb < 0) continue;
      for (int j = 0; j < 2; ++j, ++row) {
        residuals[row] = p[nb][j] / tau[j];
        if (jac && jac[nb]) jac[nb][row * 2 + j] = 1.0 / tau[j];
      }
    }
    return true;
  }

 private:
  const GapModel& model_;
  const std::vector<Term>& terms_;
  const Layout& layout_;
  GapModel::Whitening white_;
  const std::vector<size_t>& obs_;
  std::vector<std::vector<std::vector<double>>> fixed_;  // [term][group][axis] coordinates
  std::vector<std::vector<Curve>> curves_;  // [term][position in obs_]
  std::vector<double> slopes_;
  std::vector<const double*> x_;            // [term]
  std::vector<int> n_, axis_;               // [term]
  std::vector<int> stencil_offset_;         // [term]: its groups' first entry of Coordinates
  std::vector<std::vector<int>> group_;     // [term][position in obs_]
  std::vector<std::array<double, 2>> step_; // [term][axis]: the Jacobian's step
  std::vector<int> scenario_block_;         // [position in obs_]: its calibration block or −1
  std::vector<std::vector<double>> calibration_;  // [block]: a calibration block's Jacobian
  bool shares_;                             // the window's interaction (fit.h, 1a)
};

}  // namespace

ModelFit FitTerms(const GapModel& model, const std::vector<Term>& terms,
                  const std::vector<char>& train, const ModelFit* start) {
  ModelFit fit;
  const Design& d = model.design();
  const int k_count = model.num_metrics();
  const int scenarios = d.num_scenarios();
  const int frozen = model.Frozen(terms);

  // Which groups and scenarios have fitted cells.
  std::vector<size_t> obs;
  std::vector<char> scenario_used(scenarios, 0);
  std::vector<std::vector<char>> group_used(terms.size());
  for (size_t t = 0; t < terms.size(); ++t) group_used[t].assign(model.NumGroups(terms[t]), 0);
  for (int c = 0; c < d.num_cells(); ++c) {
    if (!train[c]) continue;
    bool any = false;
    for (int k = 0; k < k_count; ++k) {
      const size_t o = static_cast<size_t>(c) * k_count + k;
      if (!model.valid(o)) continue;
      obs.push_back(o);
      any = true;
    }
    if (!any) continue;
    scenario_used[d.scenario[c]] = 1;
    for (size_t t = 0; t < terms.size(); ++t) group_used[t][model.Group(terms[t], c)] = 1;
  }
  if (obs.empty()) {
    fit.message = "no observation to fit";
    return fit;
  }

  // Start: the given fit's values, else each term's best grid node (per group).
  std::vector<std::vector<std::vector<double>>> coords(terms.size());  // [term][group][axis]
  for (size_t t = 0; t < terms.size(); ++t) {
    const Candidate& cand = model.surface(terms[t].candidate).candidate;
    const int groups = model.NumGroups(terms[t]);
    const TermFit* from = nullptr;
    if (start)
      for (const TermFit& tf : start->terms)
        if (tf.term.candidate == terms[t].candidate &&
            tf.term.scope == terms[t].scope)
          from = &tf;
    coords[t].assign(groups, std::vector<double>(cand.axes.size(), 0.0));
    for (int g = 0; g < groups; ++g)
      for (size_t a = 0; a < cand.axes.size(); ++a) {
        const int disc = terms[t].Discrete(g, static_cast<int>(a));
        double value = disc >= 0 ? cand.axes[a].nodes[disc]
                       : from    ? from->values[g][a]
                       : std::isfinite(cand.axes[a].neutral) ? cand.axes[a].neutral
                                                              : cand.axes[a].reference;
        coords[t][g][a] = model.ToCoord(terms[t].candidate, static_cast<int>(a), value);
      }
  }

  Layout layout;
  layout.term_block.resize(terms.size());
  std::vector<std::vector<double>> blocks;
  for (size_t t = 0; t < terms.size(); ++t) {
    const Candidate& cand = model.surface(terms[t].candidate).candidate;
    std::vector<int> axes;
    for (size_t a = 0; a < cand.axes.size(); ++a) {
      if (!cand.axes[a].discrete) axes.push_back(static_cast<int>(a));
    }
    layout.term_block[t].assign(model.NumGroups(terms[t]), -1);
    for (int g = 0; g < model.NumGroups(terms[t]); ++g) {
      if (!group_used[t][g] || axes.empty()) continue;
      layout.term_block[t][g] = static_cast<int>(layout.blocks.size());
      layout.blocks.push_back({static_cast<int>(t), g, -1, axes});
      std::vector<double> x;
      for (int a : axes) x.push_back(coords[t][g][a]);
      blocks.push_back(x);
    }
  }
  layout.scenario_block.assign(scenarios, -1);
  for (int s = 0; s < scenarios; ++s) {
    if (!scenario_used[s]) continue;
    layout.scenario_block[s] = static_cast<int>(layout.blocks.size());
    layout.blocks.push_back({-1, -1, s, {}});
    std::array<double, 2> n{0, 0};
    if (start && static_cast<int>(start->nuisance.size()) == scenarios) n = start->nuisance[s];
    for (int j = 0; j < 2; ++j)
      if (frozen & (1 << j)) n[j] = 0;
    blocks.push_back({n[0], n[1]});
  }

  auto* cost = new GapCost(model, terms, layout, model.Whiten(obs), coords);
  ceres::Problem::Options po;
  ceres::Problem problem(po);
  std::vector<double*> ptrs;
  for (auto& b : blocks) ptrs.push_back(b.data());
  problem.AddResidualBlock(cost, nullptr, ptrs);
  for (size_t b = 0; b < layout.blocks.size(); ++b) {
    const Layout::Block& blk = layout.blocks[b];
    if (blk.term < 0) {  // a calibration block: its frozen components held
      if (frozen == 3) {
        problem.SetParameterBlockConstant(ptrs[b]);
      } else if (frozen) {
        problem.SetManifold(ptrs[b], new ceres::SubsetManifold(2, {frozen == 1 ? 0 : 1}));
      }
      continue;
    }
    for (size_t j = 0; j < blk.axes.size(); ++j) {
      const auto& nodes = model.NodeCoords(terms[blk.term].candidate, blk.axes[j]);
      problem.SetParameterLowerBound(ptrs[b], static_cast<int>(j), nodes.front());
      problem.SetParameterUpperBound(ptrs[b], static_cast<int>(j), nodes.back());
    }
  }
  ceres::Solver::Options options;
  options.max_num_iterations = model.settings().max_iterations;
  options.linear_solver_type = ceres::DENSE_QR;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  options.function_tolerance = 1e-10;
  options.parameter_tolerance = 1e-10;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  fit.report = summary.BriefReport();
  if (!summary.IsSolutionUsable()) {
    fit.message = "the solver found no usable solution: " + summary.message;
    return fit;
  }

  // Covariance of every coordinate from the Jacobian at the solution (prior rows included).
  const int rows = cost->num_residuals();
  std::vector<int> offset;
  int total = 0;
  for (const auto& b : blocks) {
    offset.push_back(total);
    total += static_cast<int>(b.size());
  }
  Eigen::MatrixXd var = Eigen::MatrixXd::Constant(total, total, NAN);
  std::vector<double> residuals(rows);
  {
    std::vector<std::vector<double>> jb(blocks.size());
    std::vector<double*> jp;
    for (size_t b = 0; b < blocks.size(); ++b) {
      jb[b].assign(static_cast<size_t>(rows) * blocks[b].size(), 0.0);
      jp.push_back(jb[b].data());
    }
    cost->Evaluate(ptrs.data(), residuals.data(), jp.data());
    Eigen::MatrixXd j(rows, total);
    for (size_t b = 0; b < blocks.size(); ++b)
      for (int r = 0; r < rows; ++r)
        for (size_t c = 0; c < blocks[b].size(); ++c)
          j(r, offset[b] + c) = jb[b][r * blocks[b].size() + c];
    // Frozen calibration components are no parameters: their columns leave.
    std::vector<int> free;
    for (size_t b = 0; b < blocks.size(); ++b)
      for (size_t c = 0; c < blocks[b].size(); ++c)
        if ((layout.blocks[b].term >= 0 || !(frozen & (1 << c))) &&
            j.col(offset[b] + static_cast<int>(c)).squaredNorm() > 1e-20)  // no influence: NaN
          free.push_back(offset[b] + static_cast<int>(c));
    Eigen::MatrixXd jf(rows, static_cast<int>(free.size()));
    for (size_t c = 0; c < free.size(); ++c) jf.col(c) = j.col(free[c]);
    const Eigen::MatrixXd info = jf.transpose() * jf;
    Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(info);
    cod.setThreshold(1e-10);
    if (cod.rank() == static_cast<int>(free.size())) {
      const Eigen::MatrixXd inv = cod.pseudoInverse();
      for (size_t a = 0; a < free.size(); ++a)
        for (size_t b = 0; b < free.size(); ++b) var(free[a], free[b]) = inv(a, b);
      // An effect's variance: the wider of the model's and the sandwich's (robust_covariance.h).
      std::vector<long long> unit;
      for (size_t o : cost->obs()) unit.push_back(model.Unit(o));
      const Eigen::MatrixXd robust = ClusterRobustCovariance(inv, jf, residuals, unit);
      for (size_t a = 0; a < free.size(); ++a)
        if (layout.blocks[std::upper_bound(offset.begin(), offset.end(), free[a]) -
                          offset.begin() - 1].term >= 0)
          var(free[a], free[a]) = std::fmax(var(free[a], free[a]), robust(a, a));
    }
  }
  fit.data_deviance = 0;
  for (size_t i = 0; i < obs.size(); ++i) fit.data_deviance += residuals[i] * residuals[i];
  fit.prior = 0;
  for (int r = static_cast<int>(obs.size()); r < rows; ++r)
    fit.prior += residuals[r] * residuals[r];
  fit.num_obs = static_cast<int>(obs.size());

  // Back to natural units; unused groups take the mean of the used ones' coordinates.
  for (size_t t = 0; t < terms.size(); ++t) {
    const int cand_index = terms[t].candidate;
    const Candidate& cand = model.surface(cand_index).candidate;
    const int groups = model.NumGroups(terms[t]);
    TermFit tf;
    tf.term = terms[t];
    tf.group_used = group_used[t];
    std::vector<std::vector<double>> u = coords[t];
    std::vector<std::vector<double>> sd(groups, std::vector<double>(cand.axes.size(), NAN));
    for (int g = 0; g < groups; ++g) {
      const int b = layout.term_block[t][g];
      if (b < 0) continue;
      for (size_t j = 0; j < layout.blocks[b].axes.size(); ++j) {
        const int a = layout.blocks[b].axes[j];
        u[g][a] = blocks[b][j];
        sd[g][a] = std::sqrt(var(offset[b] + j, offset[b] + j));
      }
    }
    int used = 0;
    for (int g = 0; g < groups; ++g) used += group_used[t][g];
    for (int g = 0; g < groups; ++g) {
      if (group_used[t][g] || used == 0) continue;
      for (size_t a = 0; a < cand.axes.size(); ++a) {
        double sum = 0;
        for (int h = 0; h < groups; ++h) sum += group_used[t][h] ? u[h][a] : 0.0;
        u[g][a] = sum / used;
      }
    }
    tf.values.assign(groups, {});
    tf.ci_lo.assign(groups, {});
    tf.ci_hi.assign(groups, {});
    tf.at_bound.assign(groups, {});
    for (int g = 0; g < groups; ++g) {
      for (size_t a = 0; a < cand.axes.size(); ++a) {
        const auto& nodes = model.NodeCoords(cand_index, static_cast<int>(a));
        const double x = u[g][a], s = sd[g][a];
        tf.values[g].push_back(model.FromCoord(cand_index, static_cast<int>(a), x));
        const bool disc = cand.axes[a].discrete;
        const int ax = static_cast<int>(a);
        tf.ci_lo[g].push_back(disc ? tf.values[g].back()
                                   : model.FromCoord(cand_index, ax, x - 1.96 * s));
        tf.ci_hi[g].push_back(disc ? tf.values[g].back()
                                   : model.FromCoord(cand_index, ax, x + 1.96 * s));
        const double tol = 1e-6 * (nodes.back() - nodes.front());
        const Axis& axis = cand.axes[a];
        const bool low = x <= nodes.front() + tol && axis.nodes.front() > axis.min_value;
        const bool high = x >= nodes.back() - tol && axis.nodes.back() < axis.max_value;
        tf.at_bound[g].push_back(!disc && group_used[t][g] && (low || high));
        tf.ci_lo[g].back() = std::max(tf.ci_lo[g].back(), axis.min_value);
        tf.ci_hi[g].back() = std::min(tf.ci_hi[g].back(), axis.max_value);
      }
      if (group_used[t][g]) fit.num_params += static_cast<int>(cand.axes.size());
    }
    fit.terms.push_back(std::move(tf));
  }
  fit.nuisance.assign(scenarios, {0.0, 0.0});
  fit.nuisance_sd.assign(scenarios, {NAN, NAN});
  for (int s = 0; s < scenarios; ++s) {
    const int b = layout.scenario_block[s];
    if (b < 0) continue;
    fit.nuisance[s] = {blocks[b][0], blocks[b][1]};
    fit.nuisance_sd[s] = {std::sqrt(var(offset[b], offset[b])),
                          std::sqrt(var(offset[b] + 1, offset[b] + 1))};
  }
  fit.success = true;
  return fit;
}

}  // namespace depthbias::gap
