#pragma once
// Everything the diagnosis asks of the simulator, run once: the real table's cells with the base
// sensor, the base with each scenario's σ_d and hole probability nudged both ways (the
// calibration's Jacobian, by central differences over common random numbers), and every
// candidate effect at every node of its grid. The fits then work on these tables alone.

#include <string>
#include <vector>

#include "gap/candidates.h"
#include "gap/design.h"
#include "sim/sim_metrics.h"
#include "sim/stereo_sim.h"

namespace depthbias::gap {

// A field added here is added to the simulations' key (sim_cache.cpp: SimulationsKey) too.
struct SimulateOptions {
  int frames = 10;                 // simulated frames per cell
  int threads = 2;                 // cells simulated in parallel (results do not depend on it)
  double region_margin_px = 0.5;   // the metrics-only path's region margin
  double step_log_sigma = 0.1;     // central-difference step on log σ_d
  double step_logit_p = 0.3;       // central-difference step on logit p
  bool replica = false;            // also the base at a second seed (simulated replicates)
  // The base once more with each panel moved sideways by a draw uniform within ±shift_px pixels
  // (fixed by the seed and the recording's name): the simulation's own scatter (noise.h); 0: not.
  double shift_px = 1.0;
  // Every run's pixels quantized on lattices of their own phases (sim::SimParams): the model's
  // metrics are a campaign's average over the phase of the subpixel step that its placements
  // draw, not the one phase the nominal distance gives.
  bool dither_quantization = true;
  // The base once more with every panel placed this share of its distance further along its
  // line of sight: what a placement error does to each metric (placement.h); 0: not.
  double placement_probe = 0.02;
  // The valid share of every effect that moves the window (Candidate::moves_window) read with
  // each test point's panel moved sideways by a draw uniform within ±lateral_phase_px pixels of
  // its own (its recordings share it; fixed by the seed and the test point): a node's share is
  // the base's plus its departure from the base moved alike, one more simulation of the table a
  // node. The share falls by whole pixels once the window outgrows the panel; at the nominal
  // angles every test point at one distance reads the steps at one phase (at 0° the panel's two
  // sides at the same one), a campaign's at phases of their own. 0: the nominal angles.
  double lateral_phase_px = 0.5;

  bool IsValid(std::string* why) const;
};

// One candidate's metrics over its grid: table[obs · nodes + node], obs = cell · K + k, nodes in
// row-major order (axis 0 slowest). A value the simulation could not measure at a node (no valid
// sample) holds the nearest node's that could.
struct Surface {
  Candidate candidate;
  int num_nodes = 0;
  std::vector<double> table;
};

struct Simulations {
  std::vector<std::string> cell_names;  // the design's cells, to check a design against
  std::vector<int> metrics;
  sim::SensorParams sensor;             // the base sensor, every scenario of the table listed
  std::vector<double> base;             // [obs]
  std::vector<double> depth_m;          // true panel depth per cell
  std::vector<double> jac_log_sigma;    // ∂ metric / ∂ log σ_d of the cell's scenario [obs]
  std::vector<double> jac_logit_p;      // ∂ metric / ∂ logit p of the cell's scenario [obs]
  std::vector<double> replica;          // [obs] the base at seed + 1 (empty unless asked)
  std::vector<double> shifted;          // [obs] the base, panels moved sideways (shift_px)
  std::vector<double> moved;            // [obs] the base, panels placed further (moved_rel)
  double moved_rel = 0;                 // by this share of their distance
  std::vector<Surface> surfaces;        // one per candidate, in the candidates' order; the
                                        // window's metrics smoothed along continuous axes
                                        // (smooth.h)
  int runs = 0;                         // simulations of the whole table

  bool Matches(const Design& design) const;
};

// The base sensor with every scenario of the design listed (the fallback's values for those
// the sensor does not list), so that its σ_d and p can be moved one scenario at a time.
sim::SensorParams ListScenarios(const sim::SensorParams& sensor, const Design& design);

// Throws std::invalid_argument for invalid parameters or candidates.
Simulations SimulateDesign(const sim::SimParams& base, const Design& design,
                           const std::vector<Candidate>& candidates,
                           const SimulateOptions& options);

// The design's metrics [obs] with params[s] for the cells of scenario s (one SimParams for all
// when params has one element); depth_m gets each cell's true panel depth when given.
std::vector<double> SimulateValues(const std::vector<sim::SimParams>& params, const Design& design,
                                   const SimulateOptions& options,
                                   std::vector<double>* depth_m = nullptr);

// The design with each test point's panel moved sideways by a draw uniform within ±shift_px
// pixels (its recordings, named by sim::CellName at their nominal distance and angle, share it;
// fixed by base's seed): SimulateOptions::lateral_phase_px's.
Design LateralPhases(const Design& d, const sim::SimParams& base, double shift_px);

// A selection's simulation, as the diagnosis checks it against the table (the nested folds'
// held-out cells, the verification): SimulateValues, and where options.lateral_phase_px > 0
// the mean of the cells as placed and at their lateral phases (LateralPhases, `base`'s
// seed): the metrics the panel's window decides move by steps with its sub-pixel phase, and
// one phase's step is not the selection's.
std::vector<double> SimulateSelection(const std::vector<sim::SimParams>& params,
                                      const Design& design, const sim::SimParams& base,
                                      const SimulateOptions& options);

// The same with one parameter set at each width of the region_spill effect (params' own width
// is not used): [w] is SimulateValues({params with region_spill_px = spills_px[w]}). The widths
// share each cell's sensor, footprint frames and measured plane (sim::SimulateMetricsSpills).
std::vector<std::vector<double>> SimulateValuesSpills(const sim::SimParams& params,
                                                      const Design& design,
                                                      const SimulateOptions& options,
                                                      const std::vector<double>& spills_px);

// Monotone piecewise-cubic (Fritsch–Carlson) interpolation through (x[i], y[i]), x ascending,
// t clamped to [x[0], x[n − 1]].
double Pchip(const double* x, const double* y, int n, double t);

// Pchip's slope at node j: the weighted harmonic mean of the neighbouring secants, 0 where they
// differ in sign (no overshoot); one-sided at the ends.
double PchipSlope(const double* x, const double* y, int n, int j);

}  // namespace depthbias::gap
