#include "gap/unexplained.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
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

std::string PointName(const PlacementEstimate& pe, int t) {
  return "test point " + TestPointName(pe, t);
}

// The candidate groups of cells: every level of a factor and of a pair of factors that holds
// more than one test point, in the order of their names. A group inside one test point is left
// out: permuting test points as wholes leaves its score as it is, so it could never be beyond
// chance and would only hide the others (a test point is judged against the placement law).
struct Groups {
  std::vector<std::string> name;
  std::vector<std::vector<int>> cells;
};

Groups MakeGroups(const Design& d, const PlacementEstimate& pe) {
  std::map<std::string, std::vector<int>> groups;
  for (int c = 0; c < d.num_cells(); ++c)
    for (int f = 0; f < 5; ++f) {
      groups[LevelName(d.cells[c], f)].push_back(c);
      for (int g = f + 1; g < 5; ++g)
        groups[LevelName(d.cells[c], f) + " × " + LevelName(d.cells[c], g)].push_back(c);
    }
  Groups out;
  for (auto& [name, cells] : groups) {
    bool several = pe.point.empty() && cells.size() > 1;
    for (size_t i = 1; i < cells.size() && !pe.point.empty(); ++i)
      several = several || pe.point[cells[i]] != pe.point[cells[0]];
    if (!several) continue;
    out.name.push_back(name);
    out.cells.push_back(std::move(cells));
  }
  return out;
}

// The group whose mean departure carries the most of metric k's Σz²: (Σ_g z)² / (n_g · Σz²),
// the share its mean explains (the likelihood ratio of a shift in that group alone, a scan
// statistic). Its score; its index in *best. Weighting the share by the group's smallness, as
// (share)² / (n_g / n), lost a departure shared by a whole level: a far over-read of 0.5 m at
// 16 m only (1.6 placement σ a test point) was named in 2 of 5 tables, the search picking
// 16 m × 0° (two test points) whose best, permuted, is often matched by any two drawn far;
// the share names 16 m in 4 of 5 and a single test point read 1 m far as before.
double BestScore(const Groups& g, const std::vector<double>& z, int kk, int k, int* best) {
  double total = 0;
  int n = 0;
  for (size_t o = static_cast<size_t>(k); o < z.size(); o += kk)
    if (std::isfinite(z[o])) total += z[o] * z[o], ++n;
  *best = -1;
  if (n == 0 || !(total > 0)) return 0;
  double best_score = 0;
  for (size_t i = 0; i < g.cells.size(); ++i) {
    double sum = 0;
    int count = 0;
    for (int c : g.cells[i]) {
      const double v = z[static_cast<size_t>(c) * kk + k];
      if (std::isfinite(v)) sum += v, ++count;
    }
    if (count == 0) continue;
    const double share = sum * sum / count / total;
    if (share > best_score) best_score = share, *best = static_cast<int>(i);
  }
  return best_score;
}

// Test points as blocks of slots (a preset and emitter each): [block][slot] → cell or −1.
// Without placement every cell is its own block.
std::vector<std::vector<int>> MakeBlocks(const Design& d, const PlacementEstimate& pe) {
  std::vector<std::vector<int>> blocks;
  if (pe.point.empty()) {
    for (int c = 0; c < d.num_cells(); ++c) blocks.push_back({c});
    return blocks;
  }
  std::map<std::string, int> slots;
  for (int c = 0; c < d.num_cells(); ++c)
    slots.emplace(d.cells[c].preset + (d.cells[c].emitter_on ? "/on" : "/off"),
                  static_cast<int>(slots.size()));
  blocks.assign(pe.num_points, std::vector<int>(slots.size(), -1));
  for (int c = 0; c < d.num_cells(); ++c)
    blocks[pe.point[c]][slots.at(d.cells[c].preset + (d.cells[c].emitter_on ? "/on" : "/off"))] =
        c;
  return blocks;
}

// Size, standard error and form of the rest of metric k over `group_cells`.
Unexplained Describe(const GapModel& m, const std::vector<double>& mu,
                     const PlacementEstimate& pe, const std::vector<double>& z, int k,
                     const std::string& where, const std::vector<int>& group_cells,
                     double total, double p_value) {
  const Design& d = m.design();
  const int kk = d.num_metrics();
  Unexplained u;
  u.metric = InfoOf(d.metrics[k]).name;
  u.unit = InfoOf(d.metrics[k]).unit;
  u.where = where;
  // Size and form: weighted least squares of the residual on 1, D, D² (one at a time).
  double sw = 0, swr = 0, chi2 = 0, max_d = 0;
  double s[3] = {0, 0, 0}, sr[3] = {0, 0, 0};
  std::vector<int> points;
  for (int c : group_cells) {
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
  u.p_value = p_value;
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
  return u;
}

// Test points of t's light and distance (t included).
int RowSize(const PlacementEstimate& pe, int t) {
  int n = 0;
  for (int q = 0; q < pe.num_points; ++q)
    n += pe.point_light[q] == pe.point_light[t] &&
         pe.point_distance_m[q] == pe.point_distance_m[t];
  return n;
}

// Per test point: the mean residual of its recordings about the model (metric k) minus the
// mean of the other test points' of its light and distance (NaN without others or residuals).
std::vector<double> OwnDepartures(const GapModel& m, const std::vector<double>& mu,
                                  const PlacementEstimate& pe, int k) {
  const Design& d = m.design();
  const int kk = d.num_metrics();
  std::vector<double> sum(pe.num_points, 0.0), mean(pe.num_points, NAN);
  std::vector<int> count(pe.num_points, 0);
  for (int c = 0; c < d.num_cells(); ++c) {
    const size_t o = static_cast<size_t>(c) * kk + k;
    if (!m.valid(o) || !std::isfinite(mu[o])) continue;
    sum[pe.point[c]] += m.y(o) - mu[o];
    ++count[pe.point[c]];
  }
  for (int t = 0; t < pe.num_points; ++t)
    if (count[t] > 0) mean[t] = sum[t] / count[t];
  std::vector<double> own(pe.num_points, NAN);
  for (int t = 0; t < pe.num_points; ++t) {
    double others = 0;
    int n = 0;
    for (int q = 0; q < pe.num_points; ++q)
      if (q != t && std::isfinite(mean[q]) && pe.point_light[q] == pe.point_light[t] &&
          pe.point_distance_m[q] == pe.point_distance_m[t])
        others += mean[q], ++n;
    if (n > 0 && std::isfinite(mean[t])) own[t] = mean[t] - others / n;
  }
  return own;
}

// The largest share of the weighted residual of metric k that one law in distance explains over
// the whole table: max_j (Σ w·f_j·r)² / Σ w·f_j², against the same with signs drawn for test
// points as wholes. The laws: constant, ∝ D, ∝ D², and a step from each distance of the table
// but the nearest on (zero nearer: a return the camera mixes in beyond some range); the maximum
// over all of them is what the drawn signs are held against, so the extra laws are paid for in
// the p-value. Its p-value; *step_from: the step's first distance when a step explains the most
// by more than a parameter's price, also against each smooth law in one light alone, else NaN.
// With `best_light` (a table of two lights or more), each light's smooth laws (zero in the other
// lights) are among the laws tested too, and *best_light names the light whose law explains the
// most when one does (else ""): a disparity offset at sunset alone is a law ∝ D² at sunset,
// which the whole table's laws read as a step from the middle distance at half its size.
double SharedDepartureP(const GapModel& m, const std::vector<double>& mu, int k,
                        const std::vector<std::vector<int>>& blocks, const RestParams& params,
                        double* step_from, std::string* best_light = nullptr) {
  const Design& d = m.design();
  const int kk = d.num_metrics();
  std::vector<double> levels;  // the distances of the blocks' cells
  for (const auto& b : blocks)
    for (int c : b)
      if (c >= 0) levels.push_back(d.cells[c].distance_m);
  std::sort(levels.begin(), levels.end());
  levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
  const size_t nf = 3 + (levels.size() > 1 ? levels.size() - 1 : 0);
  std::vector<std::string> lights;  // each light's three smooth laws follow the nf laws
  for (const auto& b : blocks)
    for (int c : b)
      if (c >= 0 && std::find(lights.begin(), lights.end(), d.cells[c].light) == lights.end())
        lights.push_back(d.cells[c].light);
  if (lights.size() < 2) lights.clear();  // one light's laws are the whole table's
  const size_t nl = nf + 3 * lights.size();
  const size_t tested = best_light ? nl : nf;  // each light's laws: in the test, or the veto's
  auto law = [&](size_t j, const sim::Cell& cell) {
    const double dd = cell.distance_m;
    if (j >= nf) {
      if (cell.light != lights[(j - nf) / 3]) return 0.0;
      j = (j - nf) % 3;
    }
    return j == 0 ? 1.0 : j == 1 ? dd : j == 2 ? dd * dd : dd >= levels[j - 2] ? 1.0 : 0.0;
  };
  // Per test point and law: Σ w·f·r and Σ w·f².
  const size_t nb = blocks.size();
  std::vector<std::vector<double>> wfr(nb, std::vector<double>(nl, 0.0));
  std::vector<double> wff(nl, 0.0);
  for (size_t b = 0; b < nb; ++b)
    for (int c : blocks[b]) {
      if (c < 0) continue;
      const size_t o = static_cast<size_t>(c) * kk + k;
      if (!m.valid(o) || !std::isfinite(mu[o])) continue;
      const double w = 1.0 / (m.noise(o) * m.noise(o)), r = m.y(o) - mu[o];
      for (size_t j = 0; j < nl; ++j) {
        const double f = law(j, d.cells[c]);
        wfr[b][j] += w * f * r, wff[j] += w * f * f;
      }
    }
  // The best of laws [first, last) under the signs, and which.
  auto stat = [&](const std::vector<int>& sign, size_t first, size_t last, size_t* which) {
    double best = 0;
    for (size_t j = first; j < last; ++j) {
      double sum = 0;
      for (size_t b = 0; b < nb; ++b) sum += sign[b] * wfr[b][j];
      if (wff[j] > 0 && sum * sum / wff[j] > best) best = sum * sum / wff[j], *which = j;
    }
    return best;
  };
  size_t which = 0, ignored = 0;
  const std::vector<int> as_measured(nb, 1);
  const double observed = stat(as_measured, 0, tested, &which);
  // The form described: a step's distance is one more thing chosen, so a step is named only
  // when it explains more than the best smooth law by ln(test points), BIC's price of a
  // parameter (else an offset's D² would often read as a step from the middle). The smooth laws
  // are held over the whole table and in each light alone, one parameter either way: a law in
  // one light, pooled with the other's nothing, reads as a step (a disparity offset of 0.15 px
  // at sunset only, under placement scatter, was read as a step in 5 of 40 tables, and a range
  // law kept for it dropped; in 1 of 40 with each light's laws).
  *step_from = NAN;
  if (best_light) *best_light = which >= nf ? lights[(which - nf) / 3] : "";
  if (which >= 3 && which < nf) {
    const double smooth =
        std::max(stat(as_measured, 0, 3, &ignored), stat(as_measured, nf, nl, &ignored));
    if (observed - smooth > std::log(static_cast<double>(nb))) *step_from = levels[which - 2];
  }
  std::mt19937_64 rng(params.seed + 1);
  std::vector<int> sign(nb);
  int as_large = 0;
  for (int i = 0; i < params.permutations; ++i) {
    for (size_t b = 0; b < nb; ++b) sign[b] = rng() % 2 ? 1 : -1;
    as_large += stat(sign, 0, tested, &ignored) >= observed;
  }
  return (1.0 + as_large) / (1.0 + params.permutations);
}

}  // namespace

std::string TestPointName(const PlacementEstimate& pe, int t) {
  return pe.point_light[t] + " " + Num(pe.point_distance_m[t]) + " m " +
         Num(pe.point_angle_deg[t]) + "°";
}

std::string LevelName(const sim::Cell& c, int factor) {
  switch (factor) {
    case 0: return "distance " + Num(c.distance_m) + " m";
    case 1: return "angle " + Num(c.angle_deg) + "°";
    case 2: return "preset " + c.preset;
    case 3: return "light " + c.light;
    default: return std::string("emitter ") + (c.emitter_on ? "on" : "off");
  }
}

double MedianStepFrom(const GapModel& m, const std::vector<double>& mu,
                      const PlacementEstimate& pe, const std::vector<char>& cells,
                      const RestParams& params) {
  const Design& d = m.design();
  const auto at = std::find(d.metrics.begin(), d.metrics.end(), kMedianBias);
  if (at == d.metrics.end() || pe.empty()) return NAN;
  const int k = static_cast<int>(at - d.metrics.begin());
  // The test points with a marked cell, and of those only the marked cells.
  std::vector<std::vector<int>> blocks;
  for (std::vector<int>& b : MakeBlocks(d, pe)) {
    bool any = false;
    for (int& c : b) {
      if (c >= 0 && !cells[c]) c = -1;
      any = any || c >= 0;
    }
    if (any) blocks.push_back(std::move(b));
  }
  double step_from = NAN;
  const double p = SharedDepartureP(m, mu, k, blocks, params, &step_from);
  return p < params.alpha / d.num_metrics() ? step_from : NAN;
}

std::vector<Unexplained> DescribeRest(const GapModel& m, const std::vector<double>& mu,
                                      const PlacementEstimate& pe, const RestParams& params) {
  std::vector<Unexplained> out;
  const Design& d = m.design();
  const int kk = d.num_metrics();
  const std::vector<double> z = Scaled(m, mu);
  const std::vector<std::vector<int>> blocks = MakeBlocks(d, pe);
  // The permuted tables, the same for every metric: test points permuted as wholes (each
  // recording to the same preset and emitter slot of another test point).
  std::mt19937_64 rng(params.seed);
  std::vector<std::vector<int>> perms(params.permutations);
  for (auto& p : perms) {
    p.resize(blocks.size());
    for (size_t j = 0; j < p.size(); ++j) p[j] = static_cast<int>(j);
    for (size_t j = p.size(); j > 1; --j) std::swap(p[j - 1], p[rng() % j]);  // Fisher–Yates
  }
  const Groups groups = MakeGroups(d, pe);
  std::vector<double> zp(z.size());
  for (int k = 0; k < kk; ++k) {
    double total = 0;
    int n = 0;
    for (int c = 0; c < d.num_cells(); ++c) {
      const double v = z[static_cast<size_t>(c) * kk + k];
      if (std::isfinite(v)) total += v * v, ++n;
    }
    if (n == 0 || ChiSquareSurvival(total, n) >= params.alpha / kk) continue;
    int best = -1;
    const double observed = BestScore(groups, z, kk, k, &best);
    if (best < 0) continue;
    int as_large = 0;
    for (const auto& p : perms) {
      std::fill(zp.begin(), zp.end(), NAN);
      for (size_t b = 0; b < blocks.size(); ++b)
        for (size_t slot = 0; slot < blocks[b].size(); ++slot) {
          const int to = blocks[b][slot], from = blocks[p[b]][slot];
          if (to >= 0 && from >= 0)
            zp[static_cast<size_t>(to) * kk + k] = z[static_cast<size_t>(from) * kk + k];
        }
      int ignored = -1;
      as_large += BestScore(groups, zp, kk, k, &ignored) >= observed;
    }
    const double p_value = (1.0 + as_large) / (1.0 + params.permutations);
    if (p_value < params.alpha / kk) {
      // In the median bias, a departure found at one distance is described over every distance
      // from it on where that explains more of the weighted residual (Σ w·r)² / Σ w, one
      // parameter either way: the search reads one level, so a step of 0.5 m from 8 m on can
      // be named at 8 m alone, where the noise and the placement scatter are smallest.
      std::string where = groups.name[best];
      std::vector<int> cells = groups.cells[best];
      double level = NAN;
      for (const sim::Cell& c : d.cells)
        if (groups.name[best] == LevelName(c, 0)) level = c.distance_m;
      if (d.metrics[k] == kMedianBias && std::isfinite(level)) {
        auto explained = [&](const std::vector<int>& set) {
          double swr = 0, sw = 0;
          for (int c : set) {
            const size_t o = static_cast<size_t>(c) * kk + k;
            if (!m.valid(o) || !std::isfinite(mu[o])) continue;
            const double w = 1.0 / (m.noise(o) * m.noise(o));
            swr += w * (m.y(o) - mu[o]), sw += w;
          }
          return sw > 0 ? swr * swr / sw : 0.0;
        };
        std::vector<int> onward;
        for (int c = 0; c < d.num_cells(); ++c)
          if (d.cells[c].distance_m >= level) onward.push_back(c);
        if (onward.size() > cells.size() && explained(onward) > explained(cells)) {
          where = "distance ≥ " + Num(level) + " m";
          cells = onward;
        }
      }
      out.push_back(Describe(m, mu, pe, z, k, where, cells, total, p_value));
      continue;
    }
    // Permutations keep what the whole table shares. In the median bias a departure of every
    // test point, constant or growing with distance, is tested by signs drawn for test points
    // as wholes: a placement is as likely short as long.
    if (d.metrics[k] != kMedianBias || pe.empty()) continue;
    double step_from = NAN;
    std::string light;
    const double p_shared = SharedDepartureP(m, mu, k, blocks, params, &step_from, &light);
    if (p_shared >= params.alpha / kk) continue;
    std::vector<int> cells;
    for (int c = 0; c < d.num_cells(); ++c)
      if (!(d.cells[c].distance_m < step_from) && (light.empty() || d.cells[c].light == light))
        cells.push_back(c);  // step_from NaN: every cell (of the light)
    if (!light.empty()) {  // one light's smooth law: its form read over that light's cells
      out.push_back(Describe(m, mu, pe, z, k, "light " + light, cells, total, p_shared));
      continue;
    }
    if (std::isnan(step_from)) {
      out.push_back(Describe(m, mu, pe, z, k, "every recording", cells, total, p_shared));
      continue;
    }
    // A step: the same departure at every distance from step_from on, none nearer.
    Unexplained u = Describe(m, mu, pe, z, k, "distance ≥ " + Num(step_from) + " m", cells,
                             total, p_shared);
    u.form = "step from " + Num(step_from) + " m";
    u.size_at_max = u.size;
    out.push_back(u);
  }
  // The test points placed beyond the placement law, in the median bias.
  for (int k = 0; k < kk && !pe.empty(); ++k) {
    if (d.metrics[k] != kMedianBias) continue;
    double total = 0;
    for (size_t o = static_cast<size_t>(k); o < z.size(); o += kk)
      if (std::isfinite(z[o])) total += z[o] * z[o];
    const std::vector<double> own = OwnDepartures(m, mu, pe, k);
    for (int t = 0; t < pe.num_points; ++t) {
      if (!pe.flagged[k][t] || !std::isfinite(own[t])) continue;
      const std::string where = PointName(pe, t);
      bool listed = false;
      for (const Unexplained& u : out)
        listed = listed || (u.metric == "median_bias_m" && u.where == where);
      if (listed) continue;
      std::vector<int> cells;
      for (int c = 0; c < d.num_cells(); ++c)
        if (pe.point[c] == t) cells.push_back(c);
      const double dz = std::fabs(pe.departure_z[k][t]);
      Unexplained u = Describe(m, mu, pe, z, k, where, cells, total,
                               std::erfc(dz / std::sqrt(2.0)));
      // Its size: how far it reads from the other test points of its light and distance, with
      // the placement law's scatter of the difference as its standard error.
      const double law = pe.Law(k, d.metrics[k], pe.point_distance_m[t]);
      const int others = RowSize(pe, t) - 1;
      u.size = u.size_at_max = own[t];
      u.size_se = others > 0 ? law * std::sqrt(1.0 + 1.0 / others) : NAN;
      u.form = "one test point";
      u.beyond_placement_law = true;
      out.push_back(u);
    }
  }
  std::sort(out.begin(), out.end(),
            [](const Unexplained& a, const Unexplained& b) { return a.chi2 > b.chi2; });
  return out;
}

}  // namespace depthbias::gap
