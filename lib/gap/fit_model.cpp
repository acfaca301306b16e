// The gap model of fit.h: its observations, noise and whitening blocks, the candidates' grid
// coordinates, and the departures and predictions of a fit (the fits themselves: fit.cpp).
#include "gap/fit.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <Eigen/Dense>

#include "gap/smooth.h"

namespace depthbias::gap {

bool FitSettings::IsValid(std::string* why) const {
  if (!(tau_log_sigma > 0) || !(tau_logit_p > 0) || !std::isfinite(huber_k) ||
      max_iterations < 1) {
    if (why) *why = "fit settings: prior widths must be > 0, huber_k finite, iterations >= 1";
    return false;
  }
  return true;
}

GapModel::GapModel(const Design& design, const Simulations& sims, const NoiseEstimate& noise,
                   const FitSettings& settings, const PlacementEstimate* placement)
    : design_(design), sims_(sims), settings_(settings) {
  const bool blocks = placement && !placement->empty();
  const int k_count = design.num_metrics();
  const size_t n = design.real.size();
  y_ = design.real;
  sigma_.assign(n, NAN);
  total_.assign(n, NAN);
  block_.assign(n, -1);
  shared_.assign(n, 0.0);
  valid_.assign(n, 0);
  phi_.assign(2 * static_cast<size_t>(k_count), 1.0);
  for (int c = 0; c < design.num_cells(); ++c)
    for (int k = 0; k < k_count; ++k) {
      const size_t o = static_cast<size_t>(c) * k_count + k;
      sigma_[o] = noise.Of(design, sims, c, k);
      const double tau = blocks ? placement->Tau(k, c) : 0.0;
      total_[o] = std::sqrt(sigma_[o] * sigma_[o] + tau * tau);
      if (blocks) block_[o] = placement->point[c];
      if (blocks) shared_[o] = placement->Shared(k, design.metrics[k], placement->point[c]);
      valid_[o] = std::isfinite(y_[o]) && std::isfinite(sims.base[o]) && sigma_[o] > 0 &&
                  std::isfinite(total_[o]);
    }
  // The median's placement law, relative to distance, at each cell: the width of a range law's
  // average over where the panel may stand.
  std::vector<double> rel(design.num_cells(), 0.0);
  const auto kmed = std::find(design.metrics.begin(), design.metrics.end(), kMedianBias);
  if (blocks && kmed != design.metrics.end())
    for (int c = 0; c < design.num_cells(); ++c) {
      const double dist = design.cells[c].distance_m;
      rel[c] = placement->Law(static_cast<int>(kmed - design.metrics.begin()), kMedianBias, dist) /
               dist;
    }
  own_of_.assign(sims.surfaces.size(), -1);
  for (size_t i = 0; i < sims.surfaces.size(); ++i)
    if (blocks && sims.surfaces[i].candidate.range_law) {
      own_of_[i] = static_cast<int>(own_.size());
      own_.push_back(AverageOverPlacement(design, sims, sims.surfaces[i], rel));
    }
  for (const Surface& s : sims.surfaces) {
    std::vector<std::vector<double>> axes;
    for (const Axis& a : s.candidate.axes) {
      std::vector<double> c;
      for (double v : a.nodes) c.push_back(Coordinate(a, v));
      axes.push_back(c);
    }
    coords_.push_back(axes);
  }
  absorbs_.assign(sims.surfaces.size(), 0);
  // H of (1a): the disparity offset's nodes, per window observation, by median departure.
  int offset = -1;
  for (size_t i = 0; i < sims.surfaces.size(); ++i)
    if (sims.surfaces[i].candidate.effect == "disparity_offset" &&
        sims.surfaces[i].candidate.axes.size() == 1)
      offset = static_cast<int>(i);
  // Built whatever the setting, so that a copy may read the window at the joint depth
  // (JointWindow); SharesWindow decides where it is read.
  if (kmed == design.metrics.end() || offset < 0) return;
  median_k_ = static_cast<int>(kmed - design.metrics.begin());
  window_m_.assign(n, {});
  window_h_.assign(n, {});
  const Surface& off = surface(offset);
  for (size_t o = 0; o < n; ++o) {
    const size_t om = o - o % k_count + median_k_;
    // The window's metrics, and the valid share: a window grown past the panel takes in what
    // gives no depth beside it (its nodes are kept as simulated: smooth.h).
    const int metric = design.metrics[o % k_count];
    if (!InfoOf(metric).window && metric != kValidPct) continue;
    std::vector<std::pair<double, double>> nodes;
    for (int j = 0; j < off.num_nodes; ++j) {
      const double m = off.table[om * off.num_nodes + j] - sims.base[om];
      const double h = off.table[o * off.num_nodes + j] - sims.base[o];
      if (std::isfinite(m) && std::isfinite(h)) nodes.push_back({m, h});
    }
    std::sort(nodes.begin(), nodes.end());
    for (size_t j = 0; j < nodes.size();) {  // nodes of one median departure: their mean
      size_t end = j;
      double sum = 0;
      for (; end < nodes.size() && nodes[end].first == nodes[j].first; ++end)
        sum += nodes[end].second;
      window_m_[o].push_back(nodes[j].first);
      window_h_[o].push_back(sum / static_cast<double>(end - j));
      j = end;
    }
    if (window_m_[o].size() < 2) window_m_[o].clear(), window_h_[o].clear();
  }
}

bool GapModel::SharesWindow(const std::vector<Term>& terms) const {
  int moving = 0;
  for (const Term& t : terms) moving += surface(t.candidate).candidate.moves_window;
  return settings_.joint_window && moving >= 2 && !window_m_.empty();
}

double GapModel::WindowResponse(size_t obs, double m) const {
  const auto& x = window_m_[obs];
  return Pchip(x.data(), window_h_[obs].data(), static_cast<int>(x.size()), m);
}

double GapModel::WindowInteraction(const std::vector<Term>& terms, const double* const* u,
                                   size_t obs) const {
  if (window_m_.empty() || window_m_[obs].empty()) return 0.0;
  const size_t om = obs - obs % num_metrics() + median_k_;
  double total = 0, parts = 0;
  for (size_t t = 0; t < terms.size(); ++t) {
    if (!surface(terms[t].candidate).candidate.moves_window) continue;
    const double m = Delta(terms[t], u[t], om);
    total += m;
    parts += WindowResponse(obs, m);
  }
  return WindowResponse(obs, total) - parts;
}

int GapModel::Frozen(const std::vector<Term>& terms) const {
  int mask = 0;
  for (const Term& t : terms) mask |= absorbs_[t.candidate];
  return mask;
}

void GapModel::SetDispersion(const std::vector<double>& phi) {
  const size_t k_count = static_cast<size_t>(num_metrics());
  if (phi.size() == k_count) {
    phi_ = phi;
    phi_.insert(phi_.end(), phi.begin(), phi.end());
  } else if (phi.size() == 2 * k_count) {
    phi_ = phi;
  } else {
    throw std::invalid_argument("dispersion: not one or two values per compared metric");
  }
}

double GapModel::weight(size_t obs) const {
  const size_t k = obs % num_metrics();
  const double s = sigma_[obs], t = placement(obs);
  return 1.0 / std::sqrt(phi_[k] * s * s + phi_[num_metrics() + k] * t * t);
}

double GapModel::DataDeviance(const std::vector<double>& mu, const std::vector<char>& cells,
                              std::map<long long, double>* per_unit) const {
  const int k_count = num_metrics();
  std::vector<size_t> obs;
  for (size_t o = 0; o < mu.size(); ++o)
    if (valid(o) && cells[o / k_count] && std::isfinite(mu[o])) obs.push_back(o);
  const Whitening w = Whiten(obs);
  double sum = 0;
  for (size_t b = 0; b + 1 < w.starts.size(); ++b) {
    const int st = w.starts[b], n = w.starts[b + 1] - st;
    double block = 0;
    for (int r = 0; r < n; ++r) {
      double e = 0;
      for (int c = 0; c <= r; ++c) {
        const size_t o = w.obs[st + c];
        e += w.linv[b][r * n + c] * (y_[o] - mu[o]);
      }
      double d;
      const double rr = Robust(e, settings_.huber_k, &d);
      sum += rr * rr;
      block += rr * rr;
    }
    if (per_unit) (*per_unit)[Unit(w.obs[st])] += block;
  }
  return sum;
}

GapModel::Whitening GapModel::Whiten(const std::vector<size_t>& obs) const {
  const int k_count = num_metrics();
  Whitening w;
  w.obs = obs;
  // Block key: (test point, metric), the metrics sharing the displacement in one block (−1);
  // a recording without a test point stands alone. Within a block, metric by metric (the
  // median first: the spreads are whitened given it).
  auto key = [&](size_t o) {
    return block_[o] < 0 ? std::make_pair(-1 - static_cast<long long>(o), 0)
                         : std::make_pair(static_cast<long long>(block_[o]),
                                          settings_.joint_placement && shared_[o] != 0
                                              ? -1
                                              : static_cast<int>(o % k_count));
  };
  std::stable_sort(w.obs.begin(), w.obs.end(), [&](size_t a, size_t b) {
    return key(a) != key(b) ? key(a) < key(b) : a % k_count < b % k_count;
  });
  for (size_t i = 0; i < w.obs.size();) {
    size_t j = i;
    while (j < w.obs.size() && key(w.obs[j]) == key(w.obs[i])) ++j;
    const int n = static_cast<int>(j - i);
    Eigen::MatrixXd cov(n, n);
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c) {
        const size_t a = w.obs[i + r], b = w.obs[i + c];
        const size_t ka = a % k_count, kb = b % k_count;
        const double phi = phi_[ka], ta = placement(a), tb = placement(b);
        const double psi = ka == kb ? phi_[k_count + ka]
                                    : std::sqrt(phi_[k_count + ka] * phi_[k_count + kb]) *
                                          shared_[a] * shared_[b];
        cov(r, c) = psi * ta * tb + (r == c ? phi * sigma_[a] * sigma_[a] : 0.0);
      }
    const Eigen::MatrixXd l = cov.llt().matrixL();
    const Eigen::MatrixXd linv =
        l.triangularView<Eigen::Lower>().solve(Eigen::MatrixXd::Identity(n, n));
    std::vector<double> flat(static_cast<size_t>(n) * n, 0.0);
    for (int r = 0; r < n; ++r)
      for (int c = 0; c <= r; ++c) flat[r * n + c] = linv(r, c);
    w.starts.push_back(static_cast<int>(i));
    w.linv.push_back(std::move(flat));
    i = j;
  }
  w.starts.push_back(static_cast<int>(w.obs.size()));
  return w;
}

const char* ScopeName(Scope scope) {
  switch (scope) {
    case Scope::kPerLight: return "per_light";
    case Scope::kPerScenario: return "per_scenario";
    default: return "shared";
  }
}

int ScopeGroups(const Design& d, Scope scope) {
  switch (scope) {
    case Scope::kPerLight: return d.num_lights();
    case Scope::kPerScenario: return d.num_scenarios();
    default: return 1;
  }
}

int ScopeGroupOf(const Design& d, Scope scope, int scenario) {
  switch (scope) {
    case Scope::kPerLight: return d.scenario_light[scenario];
    case Scope::kPerScenario: return scenario;
    default: return 0;
  }
}

std::string ScopeGroupName(const Design& d, Scope scope, int group) {
  switch (scope) {
    case Scope::kPerLight: return d.light_names[group];
    case Scope::kPerScenario: return d.scenario_names[group];
    default: return "all";
  }
}

bool ScopeApplies(const Design& d, Scope scope) {
  const int groups = ScopeGroups(d, scope);
  if (scope == Scope::kPerLight)
    return groups > 1 && groups < d.num_scenarios() &&
           static_cast<int>(d.scenario_light.size()) == d.num_scenarios();
  return groups > 1;
}

int GapModel::NumGroups(const Term& t) const { return ScopeGroups(design_, t.scope); }

int GapModel::Group(const Term& t, int cell) const {
  return ScopeGroupOf(design_, t.scope, design_.scenario[cell]);
}

double GapModel::ToCoord(int candidate, int axis, double value) const {
  return Coordinate(sims_.surfaces[candidate].candidate.axes[axis], value);
}

double GapModel::FromCoord(int candidate, int axis, double coord) const {
  return sims_.surfaces[candidate].candidate.axes[axis].log_scale ? std::exp(coord) : coord;
}

GapModel GapModel::JointWindow() const {
  GapModel out = *this;
  out.settings_.joint_window = true;
  return out;
}

GapModel GapModel::Shifted(const std::vector<double>& c) const {
  GapModel out = *this;
  for (size_t o = 0; o < out.y_.size() && o < c.size(); ++o)
    if (std::isfinite(c[o])) out.y_[o] -= c[o];
  return out;
}

GapModel GapModel::JointPlacement() const {
  GapModel out = *this;
  out.settings_.joint_placement = true;
  return out;
}

GapModel GapModel::WithoutSpreads(int candidate) const {
  GapModel out = *this;
  Surface s = surface(candidate);
  const int k_count = design_.num_metrics();
  for (size_t o = 0; o < y_.size(); ++o) {
    const int metric = design_.metrics[o % k_count];
    if (metric != kMeanMinusMedian && metric != kPlaneStd && metric != kTemporalStd) continue;
    std::fill_n(s.table.begin() + static_cast<std::ptrdiff_t>(o * s.num_nodes), s.num_nodes,
                sims_.base[o]);
  }
  if (out.own_of_[candidate] < 0) {
    out.own_of_[candidate] = static_cast<int>(out.own_.size());
    out.own_.push_back(std::move(s));
  } else {
    out.own_[out.own_of_[candidate]] = std::move(s);
  }
  return out;
}

double GapModel::Delta(const Term& term, const double* u, size_t obs) const {
  const Surface& s = surface(term.candidate);
  const auto& axes = coords_[term.candidate];
  const double* row = &s.table[obs * s.num_nodes];
  double value;
  if (axes.size() == 1) {
    value = Pchip(axes[0].data(), row, static_cast<int>(axes[0].size()), u[0]);
  } else {
    const int n0 = static_cast<int>(axes[0].size()), n1 = static_cast<int>(axes[1].size());
    const int group = Group(term, static_cast<int>(obs / design_.num_metrics()));
    const int d0 = term.Discrete(group, 0), d1 = term.Discrete(group, 1);
    if (d0 >= 0) {
      value = Pchip(axes[1].data(), row + d0 * n1, n1, u[1]);
    } else {
      double along[64];
      for (int i = 0; i < n0; ++i)
        along[i] = d1 >= 0 ? row[i * n1 + d1] : Pchip(axes[1].data(), row + i * n1, n1, u[1]);
      value = Pchip(axes[0].data(), along, n0, u[0]);
    }
  }
  return value - sims_.base[obs];
}

std::vector<double> GapModel::Predict(const ModelFit& fit) const {
  const int k_count = num_metrics();
  std::vector<double> mu(sims_.base);
  std::vector<Term> terms;
  for (const TermFit& t : fit.terms) terms.push_back(t.term);
  const bool shares = SharesWindow(terms);
  std::vector<std::array<double, 2>> u(terms.size());
  std::vector<const double*> at(terms.size());
  for (size_t o = 0; o < mu.size(); ++o) {
    const int cell = static_cast<int>(o / k_count);
    for (size_t i = 0; i < terms.size(); ++i) {
      const auto& values = fit.terms[i].values[Group(terms[i], cell)];
      for (size_t a = 0; a < values.size(); ++a)
        u[i][a] = ToCoord(terms[i].candidate, static_cast<int>(a), values[a]);
      at[i] = u[i].data();
      mu[o] += Delta(terms[i], u[i].data(), o);
    }
    if (shares) mu[o] += WindowInteraction(terms, at.data(), o);
    if (!fit.nuisance.empty()) {
      const auto& n = fit.nuisance[design_.scenario[cell]];
      mu[o] += sims_.jac_log_sigma[o] * n[0] + sims_.jac_logit_p[o] * n[1];
    }
  }
  return mu;
}

}  // namespace depthbias::gap
