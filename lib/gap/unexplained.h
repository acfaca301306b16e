#pragma once
// What no registered effect explains (diagnose.h, step 5, open world): where the rest of the gap
// lies, its size and its form, judged against what noise and placement alone would give.

#include <string>
#include <vector>

#include "gap/diagnose.h"
#include "gap/fit.h"
#include "gap/placement.h"

namespace depthbias::gap {

// A level of one factor of a cell as text: 0 distance ("distance 16 m"), 1 angle, 2 preset,
// 3 light, 4 emitter.
std::string LevelName(const sim::Cell& cell, int factor);
// A test point as text: "sunset 12 m 20°".
std::string TestPointName(const PlacementEstimate& placement, int t);

struct RestParams {
  double alpha = 0.05;      // a metric's rest is described if p < alpha / metrics
  int permutations = 999;   // permuted tables
  std::uint64_t seed = 20261124;  // of the permutations (the result is reproducible)
};

// The rest of the gap after a model (mu: its prediction of every observation). For each metric
// whose Σz² is significant (χ²), the group of cells (a level of a factor or of a pair of
// factors, holding several test points) whose mean departure explains the largest share of the
// metric's Σz² is described when it is beyond chance: its score is compared with the best
// score of tables whose test points were permuted as wholes (each recording to the same preset
// and emitter slot of another test point), so that heavy-tailed, skewed or bounded residuals
// and the placement a test point's recordings share are the reference, not a normal law.
// Permutations keep what the whole table shares; in the median bias, a departure of every test
// point (constant, ∝ D or ∝ D²), of every test point from some distance on (a step: a return
// the camera mixes in beyond some range), or of every test point of one light (a smooth law in
// that light, none in the others: an offset at sunset alone) is tested against signs drawn for
// test points as wholes (a placement is as likely short as long), the best of those laws
// against the best of the drawn tables', and described as "every recording", "distance ≥ X m"
// or "light L".
// Test points the placement estimate flags in the median bias (a panel set off by more than its
// law allows) are listed too, as one test point each, sized from the other test points of its
// light and distance. Sorted by χ², largest first.
std::vector<Unexplained> DescribeRest(const GapModel& model, const std::vector<double>& mu,
                                      const PlacementEstimate& placement,
                                      const RestParams& params);

// The median bias's shared departure alone, whatever group DescribeRest names: the first
// distance of a step (the same departure from there on, none nearer) when the signs test
// above finds the shared departure beyond chance and a step explains more of it than every
// smooth law in distance by more than a parameter's price; NaN otherwise. A step found at one
// distance by the group search is described as a level ("distance 8 m", or "distance ≥ 8 m"),
// which says nothing of whether a law in distance would do as well. Read over the cells marked
// in `cells` alone (an outer fold's training cells).
double MedianStepFrom(const GapModel& model, const std::vector<double>& mu,
                      const PlacementEstimate& placement, const std::vector<char>& cells,
                      const RestParams& params);

}  // namespace depthbias::gap
