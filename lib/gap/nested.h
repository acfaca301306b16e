#pragma once
// The nested cross-validation of the diagnosis (diagnose.h, step 4) and the description of what
// no registered effect explains (step 5, open world).

#include <vector>

#include "gap/diagnose.h"
#include "gap/fit.h"

namespace depthbias::gap {

// Every outer fold: noise, placement, calibration, φ, scope and selection fitted on the other
// cells (the inner cross-validation over the same folds), then its held-out cells predicted
// with the fold's selection added and simulated with it. `full` gives the units of the stats'
// validity only; each fold's z is in its own noise units.
Nested RunNested(const Design& design, const Simulations& sims, const sim::SimParams& base,
                 const DiagnoseParams& params, const std::vector<int>& fold, int num_folds,
                 const GapModel& full);

// The rest of the gap after a model (mu: its prediction of every observation): for each metric
// whose Σz² is significant (χ², p < alpha / metrics), the factor cells its mean departure is most
// concentrated in, its size there and its form in distance.
std::vector<Unexplained> DescribeRest(const GapModel& model, const std::vector<double>& mu,
                                      const PlacementEstimate& placement, double alpha);

// The cells of `design` marked in `cells`, scenarios and metrics kept.
Design Subset(const Design& design, const std::vector<char>& cells);

}  // namespace depthbias::gap
