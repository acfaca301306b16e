#pragma once
// The nested cross-validation of the diagnosis (diagnose.h, step 4).

#include <string>
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

// Each fold's selection restricted to the effects in `keep` (at the fold's fitted values) and
// simulated again on its held-out cells, where the restriction leaves out one of its effects:
// sets n->kept, simulated_kept, gain_simulated_kept and share_moved_kept. False (those four
// cleared) where no fold selected an effect outside `keep`, the folds were not simulated, or a
// simulation failed. `fold` and `full` as given to RunNested.
bool RestrictNested(const Design& design, const Simulations& sims, const sim::SimParams& base,
                    const DiagnoseParams& params, const std::vector<int>& fold,
                    const GapModel& full, const std::vector<std::string>& keep, Nested* n);

// An effect's own part in an outer fold (the j-th of its selection): the share of the fold's
// calibrated Σz² that comes back when it is left out [0], and that share in the metrics it moves
// [1] (NaN: its change moved nothing there). False where the fold was not simulated.
bool OwnPart(const NestedFold& f, size_t j, double part[2]);

}  // namespace depthbias::gap
