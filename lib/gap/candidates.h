#pragma once
// The candidate effects of the diagnosis: for each effect of the simulator's registry
// (lib/sim/effects.h), the grid of parameter values the simulator is run at. The metrics between
// grid nodes are interpolated (monotone cubic, per cell and metric): the fits then never call
// the simulator, and one set of simulations serves every fit, fold and combination.

#include <cmath>
#include <string>
#include <vector>

#include "sim/effects.h"

namespace depthbias::gap {

struct Axis {
  std::string param;          // the registry's parameter name
  std::vector<double> nodes;  // ascending
  // The value at which the effect is absent whatever the other axis holds (NaN: none, for a
  // shape parameter such as a width or a background depth).
  double neutral = 0.0;
  bool discrete = false;   // the simulator uses whole node values only (a width in pixels)
  bool log_scale = false;  // interpolated in log(value) (gains)
  double reference = 0.0;  // a size typical of the effect, for its signature
  // The registry's bounds of the parameter: a grid edge at one of them is the value itself, not
  // a sign that the data reach beyond what was simulated.
  double min_value = -INFINITY, max_value = INFINITY;
};

// The coordinate an axis's values are interpolated and smoothed in: the log for a log-scale axis.
inline double Coordinate(const Axis& axis, double value) {
  return axis.log_scale ? std::log(value) : value;
}

struct Candidate {
  std::string effect;      // registry name
  std::vector<Axis> axes;  // one or two
  // A law of the range the camera reads (its signature is the median bias: an offset's ∝ Z², a
  // scale's ∝ Z, range read for depth growing off axis): smooth in distance, never a step.
  bool range_law = false;
  // It moves the window through the measured depth, and beside another that does the window
  // follows their joint depth (fit.h, 1a): a range law, and a disparity offset that drifts
  // during the recording, whose pooled frames read the panel at its mean offset.
  bool moves_window = false;
  bool IsValid(std::string* why) const;
};

// Every effect of the registry with its default grid, in the registry's order.
std::vector<Candidate> DefaultCandidates();

// "all" or a comma-separated list of registry names (a name without a default grid is refused).
bool SelectCandidates(const std::string& list, std::vector<Candidate>* out, std::string* why);

// The effect at the given axis values.
sim::EffectSpec SpecAt(const Candidate& candidate, const std::vector<double>& values);

// True if the axis values leave the effect absent (an axis at its neutral value).
bool IsNeutral(const Candidate& candidate, const std::vector<double>& values);

}  // namespace depthbias::gap
