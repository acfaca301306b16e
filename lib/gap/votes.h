#pragma once
// What the outer folds of the nested hold-out choose (diagnose.cpp, step 4): how many select an
// effect, the part of their gap it carries, the correlated rival they prefer to it, and the
// pairs they split between. Read by the keep rule and by the "one of" names.

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "gap/diagnose.h"

namespace depthbias::gap {

// An effect's folds and its own part there, with the floors the keep rule asks of that part:
// own_need[0] a share of a fold's calibrated gap, own_need[1] of its part in the metrics the
// effect moves (DiagnoseParams::min_own_shrink_pct, min_own_moved_shrink_pct).
struct FoldVote {
  int count = 0;               // outer folds selecting it
  double pct[2] = {NAN, NAN};  // its own part (OwnPart), in %, averaged over all the folds
                               // (0 in a fold without it); NaN where a fold was not simulated
  bool known = true;           // every fold selecting it was simulated
  bool earns = false;          // selected in half the folds or more, and its own part enough
  std::string rival;           // a correlated effect the folds prefer to it (FindRival)
  int rival_count = 0;
  double rival_r = 0;
};

FoldVote VoteOf(const Nested& n, const std::string& effect, const double own_need[2]);

// Whether some fold selects `effect` without `without` and `effect` carries its own part there
// (by either floor): a rival that is not only riding beside the other.
bool EarnsWithout(const Nested& n, const std::string& effect, const std::string& without,
                  const double own_need[2]);

// The rival of `w`, the vote of an effect the table selected (`steps`): an effect correlated with
// it (|r| ≥ 0.5) that the table does not select and that EarnsWithout it, chosen by
//  - at least as many folds, where `w` earns: the held-out evidence does not prefer the one the
//    table selected;
//  - half the folds or more (so more than `w`), with its own part enough (it earns), where `w`
//    is chosen by fewer than half the folds (whatever its own part): the table's choice
//    between the two is not the folds'. An effect dropped only for its own part has no rival.
// The one with more folds, then the larger |r|, is kept in w->rival; none leaves it empty.
void FindRival(const Nested& n, const std::vector<Confounded>& correlations,
               const std::vector<SelectionStep>& steps, const std::string& effect,
               const double own_need[2], FoldVote* w);

// Two correlated effects (|r| ≥ 0.5) the outer folds split between: neither in `steps`, not
// already named together in `named`, each selected by some fold, every fold selecting one of
// them, and whichever a fold selects carrying its own part there, on average over the folds, by
// either floor. `sizes` gives each effect's size alone as text.
std::vector<Ambiguity> FoldSplits(
    const Nested& n, const std::vector<Confounded>& correlations,
    const std::vector<SelectionStep>& steps, const std::vector<Ambiguity>& named,
    const double own_need[2],
    const std::function<std::vector<std::string>(const std::vector<std::string>&)>& sizes);

}  // namespace depthbias::gap
