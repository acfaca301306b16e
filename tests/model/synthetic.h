#pragma once
// Samples with a known truth: the article's design (4 distances × 4 angles × 2 emitter rows),
// measured depths generated from a form with known parameters, optional seeded noise.

#include <random>
#include <vector>

#include "model/forms.h"
#include "model/samples.h"

namespace depthbias::model::testing {

// Design points of one scenario.
inline std::vector<Sample> ArticleDesign() {
  std::vector<Sample> out;
  size_t row = 0;
  for (int rep = 0; rep < 2; ++rep) {
    for (double d : {4.0, 8.0, 12.0, 16.0}) {
      for (double a : {0.0, 10.0, 20.0, 35.0}) {
        Sample s;
        s.distance_m = d;
        s.angle_deg = a;
        s.x.angle_rad = a * M_PI / 180.0;
        s.row = row++;
        out.push_back(s);
      }
    }
  }
  return out;
}

// Disparity forward model (forms.h): Z_t = k(α)·D·cos α, Z = f·B / (f·B/Z_t + δ), plus noise
// of `noise_m` on Z. k(α) is k_at(angle_deg).
template <class K>
std::vector<Sample> DisparityTruth(double delta_px, K k_at, double noise_m, unsigned seed,
                                   double fb = 640.0 * 0.095) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  auto samples = ArticleDesign();
  for (auto& s : samples) {
    const double zt = k_at(s.angle_deg) * s.distance_m * std::cos(s.x.angle_rad);
    const double z = fb / (fb / zt + delta_px) + noise_m * n(rng);
    s.x.depth_m = z;
    s.target_m = z - s.distance_m;
  }
  return samples;
}

}  // namespace depthbias::model::testing
