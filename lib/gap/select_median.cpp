// The rule on a kept range law and the spreads (select.h, MedianWithoutSpreads).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "gap/report_util.h"
#include "gap/select.h"

namespace depthbias::gap {

bool MedianWithoutSpreads(const GapModel& model, const ModelFit& m0,
                          const std::vector<char>& train, const std::vector<int>& fold,
                          int num_folds, ModelFit* current, HeldOut* current_ho, Selection* r) {
  // Under the law itself, D_law − D_median ~ N(−λ², 4λ²): above 9 with a chance of at most
  // Φ(−3) whatever λ (select.h).
  constexpr double kMargin = 9.0;
  const Simulations& sims = model.sims();
  const bool any_law = std::any_of(current->terms.begin(), current->terms.end(),
                                   [&](const TermFit& t) {
                                     return sims.surfaces[t.term.candidate].candidate.range_law;
                                   });
  if (!any_law) return true;
  const GapModel joint = model.JointPlacement();
  while (!r->steps.empty() && current->success && current->terms.size() == r->steps.size()) {
    std::vector<Term> terms;
    for (const TermFit& t : current->terms) terms.push_back(t.term);
    int drop = -1;
    double drop_by = kMargin, drop_without = NAN;
    std::vector<SpreadsEvidence> evidence;
    ModelFit with;  // the selection read with one displacement per test point
    for (size_t i = 0; i < current->terms.size(); ++i) {
      const int cand = current->terms[i].term.candidate;
      if (!sims.surfaces[cand].candidate.range_law) continue;
      if (!with.success) with = FitTerms(joint, terms, train, current);
      if (!with.success) break;
      const ModelFit alone = FitTerms(joint.WithoutSpreads(cand), terms, train, current);
      if (!alone.success) continue;
      const double by = with.Deviance() - alone.Deviance();
      evidence.push_back({cand, with.Deviance(), alone.Deviance()});
      if (by > drop_by) drop = static_cast<int>(i), drop_by = by, drop_without = alone.Deviance();
    }
    if (drop < 0) {
      r->spreads = std::move(evidence);
      return true;
    }
    r->dropped.push_back(r->steps[drop].effect +
                         " (a range law whose median alone, the spreads left as simulated, fits "
                         "better: deviance " + text::Num(with.Deviance()) + " with what it "
                         "does to the spreads, " + text::Num(drop_without) + " without; a median "
                         "over-read the registry does not hold)");
    std::vector<char> keep(r->steps.size(), 1);
    keep[drop] = 0;
    if (!KeepSteps(model, m0, keep, train, fold, num_folds, &r->steps, current, current_ho,
                   &r->chosen))
      return false;
  }
  return true;
}

void SpreadsEvidenceJson(records::JsonWriter& w, const std::vector<SpreadsEvidence>& all,
                         int candidate) {
  for (const SpreadsEvidence& e : all)
    if (e.candidate == candidate)
      w.BeginObject("spreads").Number("deviance_with_spreads", e.with)
          .Number("deviance_median_only", e.median_only)
          .String("reading", e.Confirms() ? "confirm" : "cannot tell").EndObject();
}

std::string SpreadsEvidenceText(const std::vector<SpreadsEvidence>& all, int candidate,
                                const std::string& effect) {
  for (const SpreadsEvidence& e : all) {
    if (e.candidate != candidate) continue;
    const double f = e.median_only - e.with;
    // Two fits of the same parameters: the deviance difference is twice the log of their
    // likelihood ratio, the odds the data give the law against the median's law alone.
    const std::string odds = f > 2 * std::log(1000.0) ? "over 1000 to 1"
                             : f >= 0                ? text::Num(std::exp(f / 2), 2) + " to 1"
                                                     : "1 to " + text::Num(std::exp(-f / 2), 2);
    const std::string by = "deviance " + text::Num(f, 2) + " lower with its departures in them "
                           "than with the median's law alone, odds of " + odds + " for it";
    if (e.Confirms()) return effect + ": the spreads confirm it (" + by + "; 9 decides)";
    return effect + ": the spreads cannot tell it from a median over-read outside the registry "
           "(" + by + "; 9, about 90 to 1, would decide either way): the over-read is measured, "
           "its cause is not";
  }
  return "";
}

}  // namespace depthbias::gap
