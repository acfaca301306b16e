#include "gap/noise.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

namespace depthbias::gap {

double MedianAbs(std::vector<double> v) {
  for (double& x : v) x = std::fabs(x);
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  double m = v[mid];
  if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + mid));
  return m;
}

double TwoSidedCritical(double p) {
  double lo = 0, hi = 40;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::erfc(mid / std::sqrt(2.0)) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double StudentT975(int dof) {
  static const double kT[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306,
                              2.262,  2.228, 2.201, 2.179, 2.160, 2.145, 2.131, 2.120,
                              2.110,  2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064,
                              2.060,  2.056, 2.052, 2.048, 2.045, 2.042};
  return dof >= 1 && dof <= 30 ? kT[dof - 1] : 1.96;
}

double NoiseEstimate::Of(const Design& d, const Simulations& s, int cell, int k) const {
  const double z = s.depth_m[cell];
  const double a = scale[k] * NoiseShape(d.metrics[k], z);
  const double q = QuantizationRms(d.metrics[k], z, s.sensor.focal_px(), s.sensor.baseline_m,
                                   s.sensor.subpixel_step_px,
                                   s.base[static_cast<size_t>(cell) * d.num_metrics() + k]);
  const double b = simulation.empty() ? 0.0 : simulation[k] * NoiseShape(d.metrics[k], z);
  return std::sqrt(a * a + b * b + q * q);
}

NoiseEstimate EstimateNoise(const Design& d, const Simulations& s,
                            const std::vector<char>& train) {
  const int kk = d.num_metrics();
  auto used = [&](int c) { return train.empty() || train[c]; };
  NoiseEstimate n;
  n.scale.assign(kk, NAN);
  n.pairs.assign(kk, 0);
  n.method.assign(kk, "");
  for (int k = 0; k < kk; ++k) {
    const int m = d.metrics[k];
    auto obs = [&](int c) { return static_cast<size_t>(c) * kk + k; };
    // The twins' differences, grouped by scenario and distance.
    std::map<std::pair<int, double>, std::vector<double>> groups;
    int count = 0;
    for (const auto& p : d.pairs) {
      if (!used(p[0]) || !used(p[1])) continue;
      const double e_on = d.real[obs(p[0])] - s.base[obs(p[0])];
      const double e_off = d.real[obs(p[1])] - s.base[obs(p[1])];
      if (!std::isfinite(e_on) || !std::isfinite(e_off)) continue;
      groups[{d.scenario[p[0]], d.cells[p[0]].distance_m}].push_back(
          (e_on - e_off) / NoiseShape(m, s.depth_m[p[0]]));
      ++count;
    }
    std::vector<double> devs;
    for (const auto& [key, g] : groups) {
      if (g.size() < 2) continue;
      double mean = 0;
      for (double v : g) mean += v;
      mean /= static_cast<double>(g.size());
      const double inflate = std::sqrt(g.size() / (g.size() - 1.0));
      for (double v : g) devs.push_back((v - mean) * inflate);
    }
    double scale = 0;
    if (static_cast<int>(devs.size()) >= kMinReplicatePairs) {
      scale = 1.4826 * MedianAbs(devs) / std::sqrt(2.0);
      n.method[k] = "replicates";
      n.pairs[k] = count;
      const double shape_scale = std::max(scale, InfoOf(m).noise_floor);
      for (const auto& [key, g] : groups) {
        EmitterGap e;
        e.k = k;
        e.scenario = key.first;
        e.distance_m = key.second;
        e.pairs = static_cast<int>(g.size());
        double mean = 0;
        for (double v : g) mean += v;
        mean /= static_cast<double>(g.size());
        // Back to the metric's unit at this distance (the shape of its first twin's depth).
        double shape = 1;
        for (const auto& p : d.pairs)
          if (d.scenario[p[0]] == key.first && d.cells[p[0]].distance_m == key.second)
            shape = NoiseShape(m, s.depth_m[p[0]]);
        e.mean = mean * shape;
        e.se = std::sqrt(2.0) * shape_scale * shape / std::sqrt(static_cast<double>(g.size()));
        e.z = e.se > 0 ? e.mean / e.se : 0;
        n.emitter.push_back(e);
      }
    } else {
      if (s.replica.empty())
        throw std::invalid_argument("noise: too few emitter on/off pairs and no simulated replica");
      std::vector<double> diffs;
      for (int c = 0; c < d.num_cells(); ++c) {
        if (!used(c)) continue;
        const double e = s.replica[obs(c)] - s.base[obs(c)];
        if (std::isfinite(e)) diffs.push_back(e / NoiseShape(m, s.depth_m[c]));
      }
      scale = diffs.empty() ? 0.0 : 1.4826 * MedianAbs(diffs);
      n.method[k] = "simulated replicates";
      n.pairs[k] = static_cast<int>(diffs.size());
    }
    if (!(scale >= InfoOf(m).noise_floor)) {
      scale = InfoOf(m).noise_floor;
      n.method[k] += " + floor";
    }
    n.scale[k] = scale;
    if (!s.shifted.empty()) {
      double ss = 0;
      int count_shifted = 0;
      for (int c = 0; c < d.num_cells(); ++c) {
        const double e = s.shifted[obs(c)] - s.base[obs(c)];
        if (!used(c) || !std::isfinite(e)) continue;
        ss += std::pow(e / NoiseShape(m, s.depth_m[c]), 2);
        ++count_shifted;
      }
      n.simulation.resize(kk, 0.0);
      n.simulation[k] = count_shifted > 0 ? std::sqrt(ss / count_shifted / 2) : 0.0;
    }
  }
  return n;
}

}  // namespace depthbias::gap
