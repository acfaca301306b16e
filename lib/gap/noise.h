#pragma once
// The replicate noise of each compared metric. From replicates: the emitter on and off rows of
// one test point are the same panel placement recorded twice, so the difference of their
// residuals (real − sim) is noise, up to the emitter's own effect. That effect is not noise: the
// simulator's emitter may change a metric the camera's does not (at 4 m the simulated emitter
// adds several valid points, the camera's about none). So the twins' differences Δ are grouped
// by scenario and distance, each group's mean (the emitter mismatch, a gap of its own, reported
// in `emitter`) removed, and the robust scale of what is left (1.4826 · median |Δ − mean|, times
// √(n/(n − 1)) for the mean removed, over √2) is the noise of one residual, after dividing each
// difference by the metric's noise shape (Z / 10 m)^e (design.h). With fewer than
// kMinReplicatePairs pairs, simulated replicates stand in: the base simulated at two seeds,
// whose difference has the variance of a residual whose real side is as noisy as the model.
// Placement and session error, which the twins share, is a variance component of its own
// (placement.h).
//
// The simulation's own scatter is a third: the base is one draw of the noise and of where the
// panel's outline falls on the pixel grid, and so is every candidate's departure from it. The
// metrics the region's window decides (mean − median, width, tilt) move by steps as pixels enter
// or leave it, and a fit that took the simulation as exact would follow those steps as if they
// were an effect. Its size: the base simulated again with each panel moved sideways by less
// than a pixel (Simulations::shifted), the root mean square of the difference over √2 (one
// draw's), in the metric's noise shape. It adds to the replicate noise in quadrature. With
// simulated replicates (whose difference already holds the simulation's noise) it errs wide.

#include <string>
#include <vector>

#include "gap/design.h"
#include "gap/simulations.h"

namespace depthbias::gap {

constexpr int kMinReplicatePairs = 6;

// The median of |v| (0.5·(a + b) of the middle two for an even count); v must not be empty.
double MedianAbs(std::vector<double> v);

// Student's t at 97.5 % for `dof` degrees of freedom (1.96 beyond the table).
double StudentT975(int dof);

// The standard normal's Φ⁻¹(1 − p/2), 0 < p ≤ 1, by bisection on erfc.
double TwoSidedCritical(double p);

// The emitter mismatch of one group of twins (a scenario at one distance): the mean over its
// test points of (real on − real off) − (sim on − sim off), in the metric's unit.
struct EmitterGap {
  int k = 0;                // compared metric
  int scenario = 0;
  double distance_m = 0;
  int pairs = 0;
  double mean = 0;          // the camera's emitter change minus the simulator's
  double se = 0;            // its standard error (the replicate noise, √2·σ/√n)
  double z = 0;             // mean / se
};

struct NoiseEstimate {
  std::vector<double> scale;        // per compared metric: noise at Z = 10 m, in its unit
  std::vector<int> pairs;           // differences it was estimated from
  std::vector<std::string> method;  // "replicates", "simulated replicates"; "+ floor" if raised
  std::vector<EmitterGap> emitter;  // every group of twins and metric (replicates only)
  std::vector<double> simulation;   // per compared metric: the simulation's own scatter at 10 m
                                    // (empty: no shifted base)

  // Noise of one observation (cell, compared metric k): the scale times the shape, the
  // simulation's own scatter times the shape, and the metric's quantization (design.h), in
  // quadrature.
  double Of(const Design& design, const Simulations& sims, int cell, int k) const;
};

// Throws std::invalid_argument if simulated replicates are needed and sims has none. Only the
// cells marked in `train` are used (all when empty).
NoiseEstimate EstimateNoise(const Design& design, const Simulations& sims,
                            const std::vector<char>& train = {});

}  // namespace depthbias::gap
