// The rule on a kept effect and the effects along the calibration (select.h, AlongCalibration),
// and the selection read beside such an effect against their joint simulation (SimulatedBeside).
#include <algorithm>
#include <cmath>
#include <exception>
#include <string>
#include <vector>

#include "gap/report_util.h"
#include "gap/select.h"

namespace depthbias::gap {
namespace {

// `kept` with its continuous axes that have a neutral value at that value, the effect absent
// (its discrete nodes stay, as FitTerms holds them). False where no such axis leaves it absent
// (a region spill's neutral is a width of 0, a node of its own).
bool AtNeutral(const Candidate& candidate, TermFit* kept) {
  bool absent = false;
  for (size_t a = 0; a < candidate.axes.size(); ++a) {
    const Axis& axis = candidate.axes[a];
    if (axis.discrete || !std::isfinite(axis.neutral)) continue;
    for (auto& group : kept->values)
      if (a < group.size()) group[a] = axis.neutral;
    absent = true;
  }
  return absent;
}

// A grouped term read as one shared set, started from its groups' mean. False where it is shared
// already or holds a discrete node (a width fitted per group is not averaged).
bool AsShared(TermFit* t) {
  if (t->term.scope == Scope::kShared || t->values.empty()) return false;
  for (const auto& row : t->term.discrete_node)
    for (int node : row)
      if (node >= 0) return false;
  std::vector<double> mean(t->values[0].size(), 0.0);
  int used = 0;
  for (size_t g = 0; g < t->values.size(); ++g) {
    if (g < t->group_used.size() && !t->group_used[g]) continue;
    for (size_t a = 0; a < mean.size(); ++a) mean[a] += t->values[g][a];
    ++used;
  }
  if (!used) return false;
  for (double& v : mean) v /= used;
  t->term.scope = Scope::kShared;
  t->term.discrete_node.resize(1);
  t->values = {mean};
  return true;
}

}  // namespace

std::vector<char> AlongCalibration(const GapModel& model, const ModelFit& m0,
                                   const ModelFit& current, const std::vector<char>& train,
                                   Selection* r) {
  const Simulations& sims = model.sims();
  const int n_cand = static_cast<int>(sims.surfaces.size());
  const double log_n = std::log(static_cast<double>(std::max(current.num_obs, 2)));
  auto bic = [&](const ModelFit& f) { return f.Deviance() + f.num_params * log_n; };
  std::vector<char> keep(r->steps.size(), 1);
  for (;;) {
    // Per kept effect, of several effects along the calibration, the one whose model without
    // the kept effect is the best by BIC is named (the registry's order named the first: a
    // drift's offset was named with the noise gain, which moves no median).
    int drop = -1, drop_named = -1;
    double drop_margin = -INFINITY, drop_with = NAN, drop_without = NAN;
    for (size_t i = 0; i < r->steps.size(); ++i) {
      if (!keep[i]) continue;
      const Candidate& kept = sims.surfaces[current.terms[i].term.candidate].candidate;
      int named = -1;
      double named_with = INFINITY, named_without = INFINITY;
      for (int e = 0; e < n_cand; ++e) {
        if (!r->effects[e].earns || !model.Absorbs(e)) continue;
        std::vector<Term> with_terms;
        ModelFit start = m0;
        for (size_t j = 0; j < current.terms.size(); ++j) {
          if (j == i || !keep[j]) continue;
          with_terms.push_back(current.terms[j].term);
          start.terms.push_back(current.terms[j]);
        }
        with_terms.push_back(r->effects[e].fit.term);
        start.terms.push_back(r->effects[e].fit);
        const ModelFit without = FitTerms(model, with_terms, train, &start);
        with_terms.push_back(current.terms[i].term);
        start.terms.push_back(current.terms[i]);
        ModelFit with = FitTerms(model, with_terms, train, &start);
        TermFit absent = current.terms[i];
        if (without.success && AtNeutral(kept, &absent)) {
          ModelFit from = without;
          from.terms.push_back(absent);
          ModelFit nested = FitTerms(model, with_terms, train, &from);
          if (nested.success && (!with.success || nested.Deviance() < with.Deviance()))
            with = std::move(nested);
        }
        if (!without.success || !with.success || bic(with) < bic(without)) continue;
        if (bic(without) < named_without)
          named = e, named_with = bic(with), named_without = bic(without);
      }
      if (named < 0 || !(named_with - named_without > drop_margin)) continue;
      drop = static_cast<int>(i), drop_named = named;
      drop_margin = named_with - named_without, drop_with = named_with,
      drop_without = named_without;
    }
    if (drop < 0) break;
    keep[drop] = 0;
    const int ci = r->chosen[drop];
    const std::string& name = r->steps[drop].effect;
    const EffectResult& other = r->effects[drop_named];
    r->ambiguous.push_back({{name, other.name},
                            {SizeText(sims.surfaces[ci].candidate, current.terms[drop]),
                             SizeText(sims.surfaces[drop_named].candidate, other.fit)},
                            NAN, "", {}});
    r->dropped.push_back(name + " (beside " + other.name +
                         ", along the calibration, it no longer earns its parameters: BIC " +
                         text::Num(drop_with) + " with it, " + text::Num(drop_without) +
                         " without)");
  }
  return keep;
}

ModelFit SimulatedBeside(const GapModel& model, const ModelFit& fit, const TermFit& beside,
                         const std::vector<char>& train, const std::vector<int>& fold,
                         int num_folds, const sim::SimParams& base,
                         const SimulateOptions& options, int rounds, int* runs, int* done) {
  ModelFit base_fit = fit;
  TermFit named = beside;
  ModelFit with = FitBeside(model, base_fit, named, train);
  // Each term's scope read again beside the named effect, by the selection's own rule on a
  // scope (select.cpp): its groups only where they are the best by BIC (the fewer win a tie) and
  // beat the shared fit on the held-out cells by more than one standard error. Alone, a
  // per-light offset can carry what a drift beside it explains (seeds 5, 1108).
  const double log_n = std::log(static_cast<double>(std::max(with.num_obs, 2)));
  auto bic = [&](const ModelFit& f) { return f.Deviance() + f.num_params * log_n; };
  auto held_out = [&](const ModelFit& f) {
    std::vector<Term> terms;
    for (const TermFit& t : f.terms) terms.push_back(t.term);
    return CrossValidate(model, terms, fold, num_folds, f, train);
  };
  for (size_t j = 0; with.success && j <= base_fit.terms.size(); ++j) {
    ModelFit alt_fit = base_fit;
    TermFit alt_named = named;
    if (!AsShared(j < base_fit.terms.size() ? &alt_fit.terms[j] : &alt_named)) continue;
    ModelFit alt = FitBeside(model, alt_fit, alt_named, train);
    if (!alt.success) continue;
    if (bic(alt) > bic(with)) {
      const HeldOut grouped = held_out(with), shared = held_out(alt);
      if (grouped.success && (!shared.success || BeatsByOneSe(model, grouped, shared))) continue;
    }
    base_fit = std::move(alt_fit);
    named = std::move(alt_named);
    with = std::move(alt);
  }
  const int phases = options.lateral_phase_px > 0 ? 2 : 1;  // SimulateSelection's runs
  for (int i = 0; i < rounds && with.success; ++i) {
    std::vector<double> c;
    try {
      c = SimulateSelection(SelectedParams(model.sims(), base, with, model.design()),
                            model.design(), base, options);
    } catch (const std::exception&) {
      break;
    }
    *runs += phases;
    const std::vector<double> mu = model.Predict(with);
    for (size_t o = 0; o < c.size(); ++o) c[o] -= mu[o];
    ModelFit start = base_fit;  // the fit with the named effect removed, as FitBeside takes it
    start.terms.assign(with.terms.begin(), with.terms.end() - 1);
    start.nuisance = with.nuisance;
    ModelFit next = FitBeside(model.Shifted(c), start, with.terms.back(), train);
    if (!next.success) break;
    with = std::move(next);
    if (done) ++*done;
  }
  return with;
}

}  // namespace depthbias::gap
