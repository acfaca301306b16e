#include "gap/placement.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include <Eigen/Dense>

namespace depthbias::gap {
namespace {

// Student's t quantile for the same two-sided p with nu degrees of freedom, from the normal
// quantile z by the Cornish–Fisher expansion (Abramowitz & Stegun 26.7.5; within 1 % for
// nu >= 5 at these tail probabilities, conservative below).
double StudentCritical(double z, double nu) {
  nu = std::max(nu, 1.0);
  const double z2 = z * z, z3 = z2 * z, z5 = z3 * z2, z7 = z5 * z2;
  return z + (z3 + z) / (4 * nu) + (5 * z5 + 16 * z3 + 3 * z) / (96 * nu * nu) +
         (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / (384 * nu * nu * nu);
}

// Columns of the fixed effects for the listed cells: a common offset, the main effects and the
// two-factor interactions of the five factors (indicator coding) but light × angle, and distance
// × angle as the two laws D·(1 − cos α) and D²·(1 − cos α) (FixedEffectsWith), reduced to full
// rank. The registry's laws act through distance and angle jointly (range against depth, a
// tilt, a radial residual, edge mixing) and per scenario (light × preset) with distance; none
// makes the light change how the angle acts. A light × angle pattern is a session's placement:
// the stand of one session set off at one angle.
//
// Test points must keep degrees of freedom of their own, or the scatter cannot be estimated (its
// REML runs off to any size), nor a misplaced point be told from the law it inflates. The
// distance × angle columns are kept where the test points keep at least half their number beyond
// the fixed effects: 19 of 32 on the article's grid. With one light (a user's unit: 16 test
// points of distance × angle) they would leave 7 and are left out (with them, a point set 2 m
// far on such a unit inflates the law past flagging: Placement.AUnitOfOneLight…), and what of a
// camera law is not additive in distance and angle (a disparity offset ∝ Z² = D²·cos²α: about a
// tenth of its size at 16 m and 35°) is counted as scatter.
// Degrees of freedom the test points of `cells` keep beyond x; *points: how many there are.
int ScatterDof(const Eigen::MatrixXd& x, const Design& d, const std::vector<int>& cells,
               int* points) {
  int np = 0;
  const std::vector<int> point = TestPoints(d, &np);
  std::vector<char> seen(np, 0);
  for (int c : cells) seen[point[c]] = 1;
  *points = static_cast<int>(std::count(seen.begin(), seen.end(), 1));
  const int n = static_cast<int>(cells.size());
  Eigen::MatrixXd xt(n, x.cols() + np);
  xt.leftCols(x.cols()) = x;
  xt.rightCols(np).setZero();
  for (int i = 0; i < n; ++i) xt(i, x.cols() + point[cells[i]]) = 1.0;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> a(x), b(xt);
  a.setThreshold(1e-9);
  b.setThreshold(1e-9);
  return static_cast<int>(b.rank() - a.rank());
}

Eigen::MatrixXd FixedEffectsWith(const Design& d, const std::vector<int>& cells,
                                 bool distance_angle);

Eigen::MatrixXd FixedEffects(const Design& d, const std::vector<int>& cells) {
  Eigen::MatrixXd x = FixedEffectsWith(d, cells, true);
  if (cells.empty()) return x;
  int points = 0;
  if (ScatterDof(x, d, cells, &points) < std::max(3, (points + 1) / 2))
    x = FixedEffectsWith(d, cells, false);
  return x;
}

Eigen::MatrixXd FixedEffectsWith(const Design& d, const std::vector<int>& cells,
                                 bool distance_angle) {
  std::vector<std::vector<int>> level(5);
  std::vector<int> count(5);
  // 0: light, 1: distance, 2: angle, 3: preset, 4: emitter (Factor's order).
  for (int f = 0; f < 5; ++f) level[f] = FactorLevels(d, static_cast<Factor>(f), &count[f]);
  const int n = static_cast<int>(cells.size());
  std::vector<Eigen::VectorXd> cols;
  cols.push_back(Eigen::VectorXd::Ones(n));
  std::vector<std::vector<Eigen::VectorXd>> main(5);
  for (int f = 0; f < 5; ++f)
    for (int l = 1; l < count[f]; ++l) {
      Eigen::VectorXd v(n);
      for (int i = 0; i < n; ++i) v(i) = level[f][cells[i]] == l ? 1.0 : 0.0;
      main[f].push_back(v);
      cols.push_back(v);
    }
  for (int f = 0; f < 5; ++f)
    for (int g = f + 1; g < 5; ++g) {
      if (f == 0 && g == 2) continue;  // light × angle: no camera law of the registry has it
      if (f == 1 && g == 2) continue;  // distance × angle: its smooth part only, below
      for (const auto& a : main[f])
        for (const auto& b : main[g]) cols.push_back(a.cwiseProduct(b));
    }
  // Distance × angle as two laws. A camera law acts through the panel's depth Z = D·cos α,
  // linearly (a scale: D·cos α; a range read as depth: D·(1 − cos α)) or as its square (a
  // disparity offset or drift: D²·cos²α; a radial residual: D²·sin²α, r ∝ tan α). Beside the
  // main effects of distance and angle, what they leave is D·(1 − cos α) and D²·sin²α, and
  // sin²α = (1 − cos α)(1 + cos α) is 1.82–1.99 times 1 − cos α from 10° to 35°: two columns,
  // D·(1 − cos α) and D²·(1 − cos α). The full table of distance × angle (9 parameters on the
  // article's grid) would also take up what one test point does alone, and with two lights
  // leave a test point only its contrast with its partner of the other light (a misplaced
  // point and its partner then depart together, the other way, and which of them was misplaced
  // cannot be told); a slope a distance (3) leaves a 35° point, whose 1 − cos α sets the slope,
  // much the same.
  if (distance_angle) {
    Eigen::VectorXd c1(n), c2(n);
    for (int i = 0; i < n; ++i) {
      const sim::Cell& cell = d.cells[cells[i]];
      const double dist = cell.distance_m / 10.0;
      c1(i) = dist * (1.0 - std::cos(cell.angle_deg * M_PI / 180.0));
      c2(i) = dist * c1(i);
    }
    cols.push_back(c1);
    cols.push_back(c2);
  }
  Eigen::MatrixXd x(n, static_cast<int>(cols.size()));
  for (size_t j = 0; j < cols.size(); ++j) x.col(static_cast<int>(j)) = cols[j];
  if (n == 0) return x;
  // Keep a set of independent columns (pivoted QR).
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(x);
  qr.setThreshold(1e-9);
  const int rank = static_cast<int>(qr.rank());
  Eigen::MatrixXd out(n, rank);
  for (int j = 0; j < rank; ++j) out.col(j) = x.col(qr.colsPermutation().indices()(j));
  return out;
}

// One metric's REML problem over test-point blocks, with the per-block sums that make every
// evaluation O(T·p²): V_t = D_t + τ_t²·11ᵀ, V_t⁻¹ = D_t⁻¹ − c_t·D_t⁻¹11ᵀD_t⁻¹,
// c_t = τ_t² / (1 + τ_t²·S_t), S_t = 1ᵀD_t⁻¹1.
struct Reml {
  int p = 0;
  Eigen::MatrixXd xdx;  // Σ X_tᵀD⁻¹X_t
  Eigen::VectorXd xdy;  // Σ X_tᵀD⁻¹y
  double ydy = 0, log_d = 0;
  std::vector<Eigen::VectorXd> v;  // [t] X_tᵀD⁻¹1
  std::vector<double> s, w;        // [t] S_t, 1ᵀD⁻¹y
  std::vector<double> f0, f1;      // [t] the law's basis at the point's distance
  std::vector<double> free_tau;    // [t] > 0: a flagged point's own (large) scatter

  double Tau(int t, double a, double b) const {
    return free_tau[t] > 0 ? free_tau[t] : a * f0[t] + b * f1[t];
  }

  // Block j's departure, its recordings' mean residual about X·β, and its variance under the
  // law (a, b) with the scatter at least `floor`: Var = τ² + 1/S_j ∓ the fixed effects' share
  // (− for a point informing β, + for one predicted from the others); own = τ² + 1/S_j.
  double Departure(int j, double a, double b, double floor, const Eigen::VectorXd& beta,
                   const Eigen::MatrixXd& c_inv, bool predicted, double* var,
                   double* own) const {
    const double sj = s[j];
    const double tau = std::max(a * f0[j] + b * f1[j], floor);
    const double lev = v[j].dot(c_inv * v[j]) / (sj * sj);
    *own = tau * tau + 1.0 / sj;
    *var = *own + (predicted ? lev : -lev);
    return (w[j] - v[j].dot(beta)) / sj;
  }

  // Block j's departure variance with its scatter set to tau (as Departure's).
  double VarWith(int j, double tau, const Eigen::MatrixXd& c_inv, bool predicted) const {
    const double lev = v[j].dot(c_inv * v[j]) / (s[j] * s[j]);
    return tau * tau + 1.0 / s[j] + (predicted ? lev : -lev);
  }

  // −2 × restricted log-likelihood (constants dropped); beta and c_inv on request.
  double Objective(double a, double b, Eigen::VectorXd* beta = nullptr,
                   Eigen::MatrixXd* c_inv = nullptr) const {
    Eigen::MatrixXd xvx = xdx;
    Eigen::VectorXd xvy = xdy;
    double yvy = ydy, logv = log_d;
    for (size_t t = 0; t < s.size(); ++t) {
      const double tau = Tau(static_cast<int>(t), a, b), t2 = tau * tau;
      const double c = t2 / (1 + t2 * s[t]);
      xvx.noalias() -= c * v[t] * v[t].transpose();
      xvy -= c * w[t] * v[t];
      yvy -= c * w[t] * w[t];
      logv += std::log1p(t2 * s[t]);
    }
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(xvx);
    const Eigen::VectorXd bh = ldlt.solve(xvy);
    double logdet = 0;
    for (int i = 0; i < p; ++i) logdet += std::log(std::max(ldlt.vectorD()(i), 1e-300));
    if (beta) *beta = bh;
    if (c_inv) *c_inv = ldlt.solve(Eigen::MatrixXd::Identity(p, p));
    return logv + logdet + yvy - xvy.dot(bh);
  }
};

// Test points of the blocks already flagged.
int FlaggedBlocks(const std::vector<char>& flag, const std::vector<int>& block_point) {
  int n = 0;
  for (int t : block_point) n += flag[t] ? 1 : 0;
  return n;
}

// The law (a, b ≥ 0) minimizing the REML objective: a grid in log steps (0 included), then a
// pattern search about its best node.
void FitLaw(const Reml& r, bool two, double scale_a, double scale_b, double* a_out,
            double* b_out) {
  std::vector<double> ga = {0}, gb = {0};
  for (int i = 0; i < 16; ++i) ga.push_back(scale_a * std::pow(10.0, -3.0 + 0.25 * i));
  if (two)
    for (int i = 0; i < 16; ++i) gb.push_back(scale_b * std::pow(10.0, -3.0 + 0.25 * i));
  double best = INFINITY, a = 0, b = 0;
  for (double x : ga)
    for (double y : gb) {
      const double v = r.Objective(x, y);
      if (v < best) best = v, a = x, b = y;
    }
  double step = std::log(std::pow(10.0, 0.25));
  for (int it = 0; it < 40 && step > 1e-3; ++it) {
    bool moved = false;
    const double cand[4][2] = {{a * std::exp(step), b}, {a * std::exp(-step), b},
                               {a, b * std::exp(step)}, {a, b * std::exp(-step)}};
    for (int j = 0; j < (two ? 4 : 2); ++j) {
      const double v = r.Objective(cand[j][0], cand[j][1]);
      if (v < best) best = v, a = cand[j][0], b = cand[j][1], moved = true;
    }
    if (!moved) step *= 0.5;
  }
  *a_out = a, *b_out = b;
}

// The largest scatter at block j that the law's restricted likelihood allows: the highest τ_j
// over the laws (a, b ≥ 0) whose objective lies within 2.71 of the fit's (a one-sided 95 %
// bound, χ²₁), read on FitLaw's grid, then scaled up from its highest node by bisection. A
// point is judged beyond the law only beyond this: few test points read the law loosely.
double TauUpper(const Reml& r, int j, double a, double b, bool two, double scale_a,
                double scale_b) {
  const double limit = r.Objective(a, b) + 2.71;
  auto tau = [&](double x, double y) { return x * r.f0[j] + y * r.f1[j]; };
  double bx = a, by = b;
  std::vector<double> ga = {0}, gb = {0};
  for (int i = 0; i < 16; ++i) ga.push_back(scale_a * std::pow(10.0, -3.0 + 0.25 * i));
  if (two)
    for (int i = 0; i < 16; ++i) gb.push_back(scale_b * std::pow(10.0, -3.0 + 0.25 * i));
  for (double x : ga)
    for (double y : gb)
      if (tau(x, y) > tau(bx, by) && r.Objective(x, y) <= limit) bx = x, by = y;
  double lo = 1, hi = 2;
  while (hi < 1e3 && r.Objective(hi * bx, hi * by) <= limit) lo = hi, hi *= 2;
  for (int it = 0; it < 20; ++it) {
    const double mid = std::sqrt(lo * hi);
    (r.Objective(mid * bx, mid * by) <= limit ? lo : hi) = mid;
  }
  return lo * tau(bx, by);
}

}  // namespace

std::vector<int> TestPoints(const Design& d, int* num_points) {
  std::map<std::string, int> ids;
  std::vector<int> out;
  for (const sim::Cell& c : d.cells) {
    std::ostringstream key;
    key << c.light << '|' << c.distance_m << '|' << c.angle_deg;
    const auto it = ids.emplace(key.str(), static_cast<int>(ids.size())).first;
    out.push_back(it->second);
  }
  *num_points = static_cast<int>(ids.size());
  return out;
}

PlacementEstimate EstimatePlacement(const Design& d, const Simulations& sims,
                                    const NoiseEstimate& noise, const std::vector<char>& train,
                                    double alpha) {
  PlacementEstimate pe;
  pe.point = TestPoints(d, &pe.num_points);
  const int np = pe.num_points;
  pe.point_distance_m.assign(np, 0);
  pe.point_angle_deg.assign(np, 0);
  pe.point_light.assign(np, "");
  for (int c = 0; c < d.num_cells(); ++c) {
    pe.point_distance_m[pe.point[c]] = d.cells[c].distance_m;
    pe.point_angle_deg[pe.point[c]] = d.cells[c].angle_deg;
    pe.point_light[pe.point[c]] = d.cells[c].light;
  }
  const int kk = d.num_metrics();
  pe.a.assign(kk, 0);
  pe.b.assign(kk, 0);
  pe.points_used.assign(kk, 0);
  pe.departure.assign(kk, std::vector<double>(np, NAN));
  pe.departure_z.assign(kk, std::vector<double>(np, NAN));
  pe.flagged.assign(kk, std::vector<char>(np, 0));
  pe.tau.assign(kk, std::vector<double>(np, 0.0));
  pe.floor_of.assign(kk, -1);
  pe.sensitivity.assign(kk, {});
  pe.tau_cell.assign(kk, {});
  std::vector<std::vector<double>> cell_loading(kk);  // [k][cell], metrics with a floor
  const auto median = std::find(d.metrics.begin(), d.metrics.end(), kMedianBias);
  if (median != d.metrics.end() && !sims.moved.empty() && sims.moved_rel > 0) {
    pe.floor_distance_m = pe.point_distance_m;
    std::sort(pe.floor_distance_m.begin(), pe.floor_distance_m.end());
    pe.floor_distance_m.erase(
        std::unique(pe.floor_distance_m.begin(), pe.floor_distance_m.end()),
        pe.floor_distance_m.end());
    for (int k = 0; k < kk; ++k) {
      if (d.metrics[k] != kPlaneStd && d.metrics[k] != kTemporalStd) continue;
      pe.floor_of[k] = static_cast<int>(median - d.metrics.begin());
      for (double dist : pe.floor_distance_m) {
        double sum = 0;
        int count = 0;
        for (int c = 0; c < d.num_cells(); ++c) {
          const size_t o = static_cast<size_t>(c) * kk + k;
          const double e = sims.moved[o] - sims.base[o];
          if (d.cells[c].distance_m != dist || !train[c] || !std::isfinite(e)) continue;
          sum += e / (sims.moved_rel * dist);
          ++count;
        }
        pe.sensitivity[k].push_back(count > 0 ? sum / count : 0.0);
      }
      std::map<std::string, std::pair<double, int>> per_scenario;  // sum, count
      auto group = [&](const sim::Cell& c) {
        std::ostringstream key;
        key << c.light << '|' << c.preset << '|' << c.distance_m;
        return key.str();
      };
      for (int c = 0; c < d.num_cells(); ++c) {
        const size_t o = static_cast<size_t>(c) * kk + k;
        const double e = sims.moved[o] - sims.base[o];
        if (!train[c] || !std::isfinite(e)) continue;
        auto& [sum, count] = per_scenario[group(d.cells[c])];
        sum += e / (sims.moved_rel * d.cells[c].distance_m);
        ++count;
      }
      // Each recording's loading: its scenario's sensitivity over its distance's (the mean of
      // every scenario's), within [0.1, 10]; 1 where either is not read.
      cell_loading[k].assign(d.num_cells(), 1.0);
      for (int c = 0; c < d.num_cells(); ++c) {
        const auto it = per_scenario.find(group(d.cells[c]));
        const size_t i = static_cast<size_t>(
            std::find(pe.floor_distance_m.begin(), pe.floor_distance_m.end(),
                      d.cells[c].distance_m) - pe.floor_distance_m.begin());
        const double mean = i < pe.sensitivity[k].size() ? std::fabs(pe.sensitivity[k][i]) : 0;
        if (it != per_scenario.end() && mean > 1e-9)
          cell_loading[k][c] =
              std::clamp(std::fabs(it->second.first / it->second.second) / mean, 0.1, 10.0);
      }
    }
  }
  const double z_crit = TwoSidedCritical(alpha / std::max(1, np));

  // The metrics come in their enum's order, the median (a core metric) first: its law is
  // known before the spreads' floors read it.
  for (int k = 0; k < kk; ++k) {
    const int metric = d.metrics[k];
    std::vector<int> cells;
    for (int c = 0; c < d.num_cells(); ++c) {
      const size_t o = static_cast<size_t>(c) * kk + k;
      if (train[c] && std::isfinite(d.real[o]) && std::isfinite(sims.base[o])) cells.push_back(c);
    }
    std::vector<char>& flag = pe.flagged[k];
    // Every recording stays in the fit (the fixed effects keep their rank); a flagged point's
    // placement gets a free, large variance, so that its mean informs neither β nor the law,
    // while its within-point contrasts (presets, emitter) still do.
    std::vector<int> rows = cells;
    std::stable_sort(rows.begin(), rows.end(),
                     [&](int x, int y) { return pe.point[x] < pe.point[y]; });
    const Eigen::MatrixXd x = FixedEffects(d, rows);
    Reml r;
    r.p = static_cast<int>(x.cols());
    r.xdx = Eigen::MatrixXd::Zero(r.p, r.p);
    r.xdy = Eigen::VectorXd::Zero(r.p);
    std::vector<int> block_point;
    std::vector<double> block_mean;  // the point's weighted mean residual (raw)
    double sum_sq = 0, mean_d = 0;
    for (size_t i = 0; i < rows.size();) {
      const int t = pe.point[rows[i]];
      Eigen::VectorXd v = Eigen::VectorXd::Zero(r.p);
      double s = 0, w = 0;
      for (; i < rows.size() && pe.point[rows[i]] == t; ++i) {
        const int c = rows[i];
        const size_t o = static_cast<size_t>(c) * kk + k;
        const double y = d.real[o] - sims.base[o];
        const double sd = noise.Of(d, sims, c, k);
        const double inv = 1.0 / (sd * sd);
        const Eigen::VectorXd xi = x.row(static_cast<int>(i)).transpose();
        r.xdx.noalias() += inv * xi * xi.transpose();
        r.xdy += inv * y * xi;
        r.ydy += inv * y * y;
        r.log_d += std::log(sd * sd);
        v += inv * xi;
        s += inv;
        w += inv * y;
        sum_sq += y * y;
      }
      r.v.push_back(v);
      r.s.push_back(s);
      r.w.push_back(w);
      const double dist = pe.point_distance_m[t];
      r.f0.push_back(metric == kMedianBias ? 1.0 : PlacementShape(metric, dist));
      r.f1.push_back(metric == kMedianBias ? dist : 0.0);
      r.free_tau.push_back(0.0);
      block_point.push_back(t);
      mean_d += dist;
    }
    const int blocks = static_cast<int>(block_point.size());
    if (blocks == 0 || r.p >= static_cast<int>(rows.size())) {
      pe.points_used[k] = 0;  // no placement degrees of freedom once the fixed effects are in
      continue;
    }
    mean_d /= blocks;
    const double rms = std::sqrt(sum_sq / static_cast<double>(rows.size())) + 1e-12;
    const bool two = metric == kMedianBias;
    const double scale_b = rms / std::max(mean_d, 1e-3);
    // The scatter block j is judged at under the law (la, lb): the largest its likelihood allows
    // there, not below the point's floor.
    auto tau_up = [&](int j, double la, double lb) {
      return std::max(TauUpper(r, j, la, lb, two, rms, scale_b),
                      pe.Floor(k, pe.point_distance_m[block_point[j]]));
    };
    double a = 0, b = 0;
    for (int iter = 0; iter < 12; ++iter) {
      FitLaw(r, two, rms, scale_b, &a, &b);
      Eigen::VectorXd beta;
      Eigen::MatrixXd c_inv;
      r.Objective(a, b, &beta, &c_inv);
      // The departures' z under the law first; a tail inflates the law it is judged by, so the
      // z's are read against their own robust scale (1.4826·median |z| of the points not
      // flagged) where that is below 1.
      std::vector<double> zs(blocks, 0.0);
      bool changed = false;
      int used = 0;
      double z_scale = 1.0;
      for (int pass = 0; pass < 2; ++pass) {
      if (pass == 1) {
        std::vector<double> az;
        for (int j = 0; j < blocks; ++j)
          if (!flag[block_point[j]]) az.push_back(std::fabs(zs[j]));
        if (!az.empty()) {
          // The robust scale of n standard normal z's has a standard error of about
          // 1.166 / √n (the median of |z|: 1 / (2·f(0.6745)·√n), times 1.4826): only what lies
          // below its one-sided 95 % low, 1 − 1.645 · 1.166 / √n, counts as the law inflated
          // (0.50 on a user's 16 test points, 0.66 on the article's 32). On tables without
          // effect of 16 test points it reads 0.3–0.7: chance, not a tail.
          std::nth_element(az.begin(), az.begin() + az.size() / 2, az.end());
          const double low =
              std::max(0.2, 1.0 - 1.645 * 1.166 / std::sqrt(static_cast<double>(az.size())));
          z_scale = std::clamp(1.4826 * az[az.size() / 2] / low, 0.2, 1.0);
        }
      }
      for (int j = 0; j < blocks; ++j) {
        const int t = block_point[j];
        if (flag[t]) continue;  // a flag stays: the search only grows (it cannot oscillate)
        double var = 0, own = 0;
        const double m = r.Departure(j, a, b, pe.Floor(k, pe.point_distance_m[t]), beta, c_inv,
                                     false, &var, &own);
        pe.departure[k][t] = m;
        zs[j] = var > 1e-3 * own ? m / std::sqrt(var) : 0.0;
        pe.departure_z[k][t] = zs[j] / z_scale;
      }
      }
      // One point at a time, the farthest beyond, and the fit made again without it: a
      // misplaced point pulls the effects it shares (its light and distance, its angle, the
      // distance × angle laws), and its neighbours may depart beyond the law only while it is
      // in.
      // A point beyond z_crit under the fitted law is flagged only if it is also beyond it
      // under the largest scatter the likelihood allows at its distance (TauUpper), the
      // farthest such point first.
      std::vector<int> beyond;
      for (int j = 0; j < blocks; ++j)
        if (!flag[block_point[j]] && std::fabs(pe.departure_z[k][block_point[j]]) > z_crit)
          beyond.push_back(j);
      std::sort(beyond.begin(), beyond.end(), [&](int i, int j) {
        return std::fabs(pe.departure_z[k][block_point[i]]) >
               std::fabs(pe.departure_z[k][block_point[j]]);
      });
      int worst = -1;
      for (int j : beyond) {
        const int t = block_point[j];
        const double var = r.VarWith(j, tau_up(j, a, b), c_inv, false);
        if (var > 0 && std::fabs(pe.departure[k][t]) / std::sqrt(var) / z_scale > z_crit) {
          worst = j;
          break;
        }
      }
      if (worst >= 0) {
        flag[block_point[worst]] = 1;
        r.free_tau[worst] = 1e3 * rms;
        changed = true;
      }
      // With few test points a misplaced one inflates the law and spills into the fixed effects
      // of its row and column (on a unit, a quarter of its departure each), so it may not stand
      // out under its own fit: when none is flagged, the point of largest |z| is also tried left
      // out (a free scatter, the law refitted) and judged as predicted from the others.
      if (!changed) {
        int top = -1;
        for (int j = 0; j < blocks; ++j)
          if (!flag[block_point[j]] && std::isfinite(zs[j]) &&
              (top < 0 || std::fabs(zs[j]) > std::fabs(zs[top])))
            top = j;
        if (top >= 0 && FlaggedBlocks(flag, block_point) == 0 && blocks > 3) {
          r.free_tau[top] = 1e3 * rms;
          double ta = 0, tb = 0;
          FitLaw(r, two, rms, scale_b, &ta, &tb);
          Eigen::VectorXd tbeta;
          Eigen::MatrixXd tc_inv;
          r.Objective(ta, tb, &tbeta, &tc_inv);
          double var = 0, own = 0;
          const double m =
              r.Departure(top, ta, tb, pe.Floor(k, pe.point_distance_m[block_point[top]]), tbeta,
                          tc_inv, true, &var, &own);
          // The law is refitted from the other points: their degrees of freedom less the
          // law's own parameters make the statistic Student's t, not normal (exact for a law
          // of one parameter). And it is read at the largest scatter their likelihood allows at
          // this point's distance (TauUpper: the shape of a law of two is loose too). Both.
          int points = 0;
          const int dof = ScatterDof(x, d, rows, &points) - 1 - (two ? 2 : 1);
          auto beyond_bound = [&] {
            const double var_up = r.VarWith(top, tau_up(top, ta, tb), tc_inv, true);
            return var_up > 0 && std::fabs(m) / std::sqrt(var_up) > z_crit;
          };
          if (dof >= 3 && var > 0 && std::fabs(m) / std::sqrt(var) > StudentCritical(z_crit, dof) &&
              beyond_bound()) {
            flag[block_point[top]] = 1;
            changed = true;
          } else {
            r.free_tau[top] = 0.0;
          }
        }
      }
      for (int j = 0; j < blocks; ++j) used += !flag[block_point[j]];
      pe.a[k] = a, pe.b[k] = b;
      pe.points_used[k] = used;
      if (!changed) break;
    }
    // The law and the fixed effects once more from the points not flagged, and every flagged
    // point's departure read as predicted from them: a point flagged while it was still in the
    // fit had part of its departure taken up by the effects it shares.
    if (FlaggedBlocks(flag, block_point) > 0) {
      FitLaw(r, two, rms, scale_b, &a, &b);
      Eigen::VectorXd beta;
      Eigen::MatrixXd c_inv;
      r.Objective(a, b, &beta, &c_inv);
      pe.a[k] = a, pe.b[k] = b;
      for (int j = 0; j < blocks; ++j) {
        const int t = block_point[j];
        if (!flag[t]) continue;
        double var = 0, own = 0;
        const double m = r.Departure(j, a, b, pe.Floor(k, pe.point_distance_m[t]), beta, c_inv,
                                     true, &var, &own);
        pe.departure[k][t] = m;
        // Its z as it was judged: at the largest scatter the others' likelihood allows there.
        var = r.VarWith(j, tau_up(j, a, b), c_inv, true);
        pe.departure_z[k][t] = var > 0 ? m / std::sqrt(var) : 0.0;
      }
    }
    for (int t = 0; t < np; ++t) {
      const double law = pe.Law(k, metric, pe.point_distance_m[t]);
      pe.tau[k][t] = flag[t] && std::isfinite(pe.departure[k][t])
                         ? std::max(law, std::fabs(pe.departure[k][t]))
                         : law;
    }
    if (!cell_loading[k].empty()) {
      // A displaced panel moves recording i's spread by s_i·u_t, and its other departures that
      // follow the panel's geometry go the same way: the test point's scatter is shared as
      // τ_t·l_i, their covariance τ_t²·l_i·l_j.
      pe.tau_cell[k].assign(d.num_cells(), 0.0);
      for (int c = 0; c < d.num_cells(); ++c)
        pe.tau_cell[k][c] = pe.tau[k][pe.point[c]] * cell_loading[k][c];
    }
  }
  EstimateCoupling(&pe);
  return pe;
}

}  // namespace depthbias::gap
