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
  valid_.assign(n, 0);
  phi_.assign(2 * static_cast<size_t>(k_count), 1.0);
  for (int c = 0; c < design.num_cells(); ++c)
    for (int k = 0; k < k_count; ++k) {
      const size_t o = static_cast<size_t>(c) * k_count + k;
      sigma_[o] = noise.Of(design, sims, c, k);
      const double tau = blocks ? placement->Tau(k, c) : 0.0;
      total_[o] = std::sqrt(sigma_[o] * sigma_[o] + tau * tau);
      if (blocks) block_[o] = placement->point[c];
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

GapModel::Whitening GapModel::Whiten(const std::vector<size_t>& obs) const {
  const int k_count = num_metrics();
  Whitening w;
  w.obs = obs;
  // Block key: (test point, metric); a recording without one stands alone.
  auto key = [&](size_t o) {
    return block_[o] < 0 ? std::make_pair(-1 - static_cast<long long>(o), 0)
                         : std::make_pair(static_cast<long long>(block_[o]),
                                          static_cast<int>(o % k_count));
  };
  std::stable_sort(w.obs.begin(), w.obs.end(), [&](size_t a, size_t b) { return key(a) < key(b); });
  for (size_t i = 0; i < w.obs.size();) {
    size_t j = i;
    while (j < w.obs.size() && key(w.obs[j]) == key(w.obs[i])) ++j;
    const int n = static_cast<int>(j - i);
    Eigen::MatrixXd cov(n, n);
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c) {
        const size_t a = w.obs[i + r], b = w.obs[i + c];
        const double phi = phi_[a % k_count], psi = phi_[k_count + a % k_count];
        const double ta = placement(a), tb = placement(b);
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
  double u[2];
  for (size_t o = 0; o < mu.size(); ++o) {
    const int cell = static_cast<int>(o / k_count);
    for (const TermFit& t : fit.terms) {
      const auto& values = t.values[Group(t.term, cell)];
      for (size_t a = 0; a < values.size(); ++a)
        u[a] = ToCoord(t.term.candidate, static_cast<int>(a), values[a]);
      mu[o] += Delta(t.term, u, o);
    }
    if (!fit.nuisance.empty()) {
      const auto& n = fit.nuisance[design_.scenario[cell]];
      mu[o] += sims_.jac_log_sigma[o] * n[0] + sims_.jac_logit_p[o] * n[1];
    }
  }
  return mu;
}

}  // namespace depthbias::gap
