#pragma once
// The noise of each compared metric, the unit the gap is measured in. From replicates: the
// emitter on and off rows of one test point are the same panel placement recorded twice, so the
// difference of their residuals (real − sim) is noise alone, whatever the gap itself is. Its
// robust scale (1.4826 · median |Δ| / √2) gives the noise of one residual, after dividing each
// difference by the metric's noise shape (Z / 10 m)^e (design.h). With fewer than
// kMinReplicatePairs pairs, simulated replicates stand in: the base simulated at two seeds,
// whose difference has the variance of a residual whose real side is as noisy as the model.

#include <string>
#include <vector>

#include "gap/design.h"
#include "gap/simulations.h"

namespace depthbias::gap {

constexpr int kMinReplicatePairs = 6;

struct NoiseEstimate {
  std::vector<double> scale;        // per compared metric: noise at Z = 10 m, in its unit
  std::vector<int> pairs;           // differences it was estimated from
  std::vector<std::string> method;  // "replicates", "simulated replicates"; "+ floor" if raised

  // Noise of one observation (cell, compared metric k): the scale times the shape, and the
  // metric's quantization in quadrature (design.h).
  double Of(const Design& design, const Simulations& sims, int cell, int k) const;
};

// Throws std::invalid_argument if simulated replicates are needed and sims has none.
NoiseEstimate EstimateNoise(const Design& design, const Simulations& sims);

}  // namespace depthbias::gap
