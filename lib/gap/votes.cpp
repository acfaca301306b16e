#include "gap/votes.h"

#include <algorithm>
#include <cmath>

#include "gap/nested.h"
#include "gap/report_util.h"

namespace depthbias::gap {
namespace {

bool Selects(const std::vector<SelectionStep>& steps, const std::string& e) {
  return std::any_of(steps.begin(), steps.end(),
                     [&](const SelectionStep& st) { return st.effect == e; });
}

}  // namespace

FoldVote VoteOf(const Nested& n, const std::string& e, const double own_need[2]) {
  FoldVote w;
  double sum[2] = {0, 0};
  for (const NestedFold& f : n.folds) {
    const auto at = std::find(f.selected.begin(), f.selected.end(), e);
    if (at == f.selected.end()) continue;
    ++w.count;
    double part[2];
    if (!OwnPart(f, static_cast<size_t>(at - f.selected.begin()), part)) {
      w.known = false;
      continue;
    }
    sum[0] += part[0];
    if (std::isfinite(part[1])) sum[1] += part[1];
  }
  const double folds = static_cast<double>(n.folds.size());
  bool enough = false;
  for (int m = 0; m < 2; ++m) {
    if (w.known && folds > 0) w.pct[m] = 100 * sum[m] / folds;
    enough |= !w.known || w.count == 0 || w.pct[m] >= own_need[m];
  }
  w.earns = enough && 2 * w.count >= static_cast<int>(folds);
  return w;
}

bool EarnsWithout(const Nested& n, const std::string& e, const std::string& without,
                  const double own_need[2]) {
  for (const NestedFold& f : n.folds) {
    const auto at = std::find(f.selected.begin(), f.selected.end(), e);
    double part[2];
    if (at == f.selected.end() || std::count(f.selected.begin(), f.selected.end(), without) ||
        !OwnPart(f, static_cast<size_t>(at - f.selected.begin()), part))
      continue;
    if (100 * part[0] >= own_need[0] || 100 * part[1] >= own_need[1]) return true;
  }
  return false;
}

void FindRival(const Nested& n, const std::vector<Confounded>& correlations,
               const std::vector<SelectionStep>& steps, const std::string& e,
               const double own_need[2], FoldVote* w) {
  const bool too_few = 2 * w->count < static_cast<int>(n.folds.size());
  if (!w->earns && !too_few) return;  // dropped for its own part: no contest of folds
  for (const Confounded& c : correlations) {
    const std::string other = c.a == e ? c.b : c.b == e ? c.a : "";
    if (other.empty() || !(std::fabs(c.correlation) >= 0.5) || Selects(steps, other)) continue;
    const FoldVote x = VoteOf(n, other, own_need);
    // Where `w` has too few folds, one that earns has half of them or more: more than it.
    const bool preferred = w->earns ? x.count >= w->count : x.earns;
    const bool better = x.count > w->rival_count ||
                        (x.count == w->rival_count &&
                         std::fabs(c.correlation) > std::fabs(w->rival_r));
    if (!preferred || !better || !EarnsWithout(n, other, e, own_need)) continue;
    w->rival = other, w->rival_count = x.count, w->rival_r = c.correlation;
  }
}

std::vector<Ambiguity> FoldSplits(
    const Nested& n, const std::vector<Confounded>& correlations,
    const std::vector<SelectionStep>& steps, const std::vector<Ambiguity>& named,
    const double own_need[2],
    const std::function<std::vector<std::string>(const std::vector<std::string>&)>& sizes) {
  std::vector<Ambiguity> out;
  auto together = [&](const std::string& a, const std::string& b) {
    auto holds = [&](const Ambiguity& m) {
      return std::count(m.effects.begin(), m.effects.end(), a) &&
             std::count(m.effects.begin(), m.effects.end(), b);
    };
    return std::any_of(named.begin(), named.end(), holds) ||
           std::any_of(out.begin(), out.end(), holds);
  };
  for (const Confounded& c : correlations) {
    if (!(std::fabs(c.correlation) >= 0.5) || Selects(steps, c.a) || Selects(steps, c.b) ||
        together(c.a, c.b))
      continue;
    int with_a = 0, with_b = 0, covered = 0;
    double own[2] = {0, 0};
    for (const NestedFold& f : n.folds) {
      double best[2] = {NAN, NAN};
      for (size_t j = 0; j < f.selected.size(); ++j) {
        if (f.selected[j] != c.a && f.selected[j] != c.b) continue;
        (f.selected[j] == c.a ? with_a : with_b) += 1;
        double part[2];
        if (!OwnPart(f, j, part)) continue;
        for (int m = 0; m < 2; ++m)
          if (std::isfinite(part[m]) && !(part[m] <= best[m])) best[m] = part[m];
      }
      if (std::isfinite(best[0]) || std::isfinite(best[1])) ++covered;
      for (int m = 0; m < 2; ++m)
        if (std::isfinite(best[m])) own[m] += best[m];
    }
    const double folds = static_cast<double>(n.folds.size());
    const double pct[2] = {100 * own[0] / folds, 100 * own[1] / folds};
    if (with_a == 0 || with_b == 0 || covered < static_cast<int>(folds) ||
        !(pct[0] >= own_need[0] || pct[1] >= own_need[1]))
      continue;
    Ambiguity split{{c.a, c.b}, {}, c.correlation, "", {}};
    split.sizes = sizes(split.effects);
    if (split.sizes.size() != 2) continue;
    split.why = "the outer folds split between them: " + c.a + " in " + std::to_string(with_a) +
                ", " + c.b + " in " + std::to_string(with_b) + " of " +
                std::to_string(n.folds.size()) + ", r = " + text::Num(c.correlation) +
                ", their own part " + text::Num(pct[0]) + " % of each fold's gap on average";
    out.push_back(split);
  }
  return out;
}

}  // namespace depthbias::gap
