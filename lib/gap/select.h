#pragma once
// One pass of the diagnosis on a set of cells (diagnose.h, steps 3–4): the calibrated base, every
// candidate alone, their signatures and confounding, and forward selection, all fitted on the
// cells marked in `train` and cross-validated over `fold` within them. The whole table runs it
// once; the nested cross-validation runs it once per outer fold, on a model whose noise and
// placement were estimated without the fold.

#include <string>
#include <vector>

#include "gap/diagnose.h"
#include "gap/fit.h"

namespace depthbias::gap {

struct Selection {
  bool success = false;
  std::string message;
  ModelFit m0;                         // the calibrated base
  HeldOut m0_ho;
  std::vector<double> dispersion;      // φ then ψ per metric, about the widest model
  std::vector<EffectResult> effects;   // every candidate alone, in the candidates' order
  std::vector<double> r2_sigma, r2_p;  // share of each signature along the calibration
  std::vector<Confounded> confounded, correlations;
  std::vector<SelectionStep> steps;
  std::vector<int> chosen;             // candidates selected, in order
  ModelFit current;                    // the selection fitted together
  HeldOut current_ho;
  // Taken by forward selection, then dropped by the step or calibration rule (Select), and why.
  std::vector<std::string> dropped;
  std::vector<Ambiguity> ambiguous;    // a dropped effect named "one of" with what explains it
  std::vector<SpreadsEvidence> spreads;  // each range law MedianWithoutSpreads kept
};

// z = (y − μ) / noise of the valid observations (NaN elsewhere).
std::vector<double> Scaled(const GapModel& model, const std::vector<double>& mu);
// Mean z² over the marked cells.
GapStat Stat(const GapModel& model, const std::vector<double>& z, const std::vector<char>& cells);
// How much of the gap beyond the noise a model removes, in %: the gap is the mean z² in excess of
// the 1 it has where the simulation matches the camera and only noise and placement remain, so
// (before − after) / (before − 1). A model that matches the camera reaches 100 % however many
// metrics sit at their noise floor (the plain ratio 1 − after / before cannot: with six of
// seven metrics at the floor and the seventh at 20, its best is 73 %). NaN when `before` has no
// excess (≤ 1): there is no gap to shrink.
double Shrink(const GapStat& before, const GapStat& after);
// Each metric's dispersions about a prediction, over the marked cells: φ_k ≥ 1, how much wider
// than the replicate noise the recordings of one test point spread about their mean (about the
// shared displacement's estimate where their loadings differ), then ψ_k ≥ 1, how much wider
// than the placement law (at φ_k) the test points' means spread (fit.h, (2)).
std::vector<double> Dispersion(const GapModel& model, const std::vector<double>& mu,
                               const std::vector<char>& cells);

// Whether a fit with more parameters beats a simpler one held out by more than one standard
// error of the difference of their held-out deviances, the test points being the independent
// units it sums over (the one-standard-error rule: Hastie, Tibshirani and Friedman, The Elements
// of Statistical Learning, 2nd ed., §7.10; within that, the simpler fit is kept). A gain that
// one test point's placement draw makes does not count as the group's.
bool BeatsByOneSe(const GapModel& model, const HeldOut& wider, const HeldOut& simpler);

// Sets the model's dispersion (about the widest model: every candidate not absorbed by the
// calibration and without a discrete axis, fitted together) and its calibration-absorbing
// candidates; the model's design and simulations are the whole table's, `placement` the
// estimate the model was built with. What forward selection takes then meets two rules, on the
// training cells alone, so that an outer fold runs the procedure the whole table runs: a range
// law is dropped where the calibrated base's median bias departs as a step (MedianStepFrom),
// and a selected effect that no longer earns its parameters beside one along the calibration is
// named "one of" with it.
Selection Select(GapModel& model, const PlacementEstimate& placement,
                 const std::vector<char>& train, const std::vector<int>& fold, int num_folds,
                 const DiagnoseParams& params);

// The rule on a kept effect and the effects along the calibration (Select). A kept effect may
// stand in for what the calibration cannot give of such an effect: a temporal drift widens the
// temporal spread, which a σ_d explains, and moves every median by its mean disparity, which only
// an offset explains. Where, with such an effect in the model (the calibration component it
// duplicates held at its configured value), a kept effect no longer earns its parameters by BIC,
// the table cannot tell the two apart: the kept one is named "one of" with it (r->ambiguous,
// r->dropped) instead (a drift of 0.8 px/s was kept as an offset of 0.15 px beside a larger σ_d).
// One at a time, the kept effect the table needs least first, each judged beside those still
// kept: two kept effects that each stand in for the other beside the drift are not both dropped
// (an offset and a scale, each no longer earning beside the other and a drift, were both
// named with it, and a 1.6 m over-read left unexplained). The model with a kept effect holds the
// one without it, so it is also fitted from that one's values with the effect at its neutral
// value, and the lower deviance kept (from the kept values alone it ended 2 to 26 above the
// model it holds). Returns which of r->steps stay; `current` is the selection fitted together
// (its terms in the steps' order), `m0` the calibrated base.
std::vector<char> AlongCalibration(const GapModel& model, const ModelFit& m0,
                                   const ModelFit& current, const std::vector<char>& train,
                                   Selection* r);

// The rule on a kept range law and the spreads (Select). A range law moves more than the
// median: a disparity offset that reads far widens every spread by (Z'/Z)², a depth scale by
// 1 + s. A median over-read that leaves the spreads alone (multipath off the ground, a reflector
// behind the panel) is neither, yet the law whose median follows it is kept wherever the
// median's gain outweighs the spreads' misfit. The selection is refitted with one displacement
// per test point in its median and spreads (GapModel::JointPlacement), and again with a kept
// range law's departures in the spreads held at the base (GapModel::WithoutSpreads, the same
// parameters, both from the kept values); where the second has a deviance lower by more than 9,
// the spreads contradict the law: it is not kept (r->dropped says why) and the median's rest is
// left to `unexplained`. Under the law itself the difference is about N(−λ², 4λ²), λ the
// spreads' evidence for its size in standard errors, so a true law is dropped with a chance of
// at most Φ(−3) = 0.13 % at any λ. Of several, the one with the largest difference goes first,
// and the rest are judged again without it (KeepSteps). False when such a refit fails.
bool MedianWithoutSpreads(const GapModel& model, const ModelFit& m0,
                          const std::vector<char>& train, const std::vector<int>& fold,
                          int num_folds, ModelFit* current, HeldOut* current_ho, Selection* r);

// Keeps the steps marked in `keep` and their terms in `current`, refitted together from the
// calibrated base `m0` on the cells marked in `train` and cross-validated over `fold` (`chosen`,
// when given, follows the steps). False when the refit fails: the kept terms then stay at the
// values they had beside the others.
bool KeepSteps(const GapModel& model, const ModelFit& m0, const std::vector<char>& keep,
               const std::vector<char>& train, const std::vector<int>& fold, int num_folds,
               std::vector<SelectionStep>* steps, ModelFit* current, HeldOut* current_ho,
               std::vector<int>* chosen = nullptr);

// The size of a fitted term as text: "param value" (per light or scenario: "param v1 / v2 / …").
std::string SizeText(const Candidate& candidate, const TermFit& term);

// The selection `fit` refitted with `beside` added (FitBeside on `model`, the window at their
// joint depth; each grouped term, `beside` too, refitted shared and kept so unless its groups
// earn both ways, as the selection's scopes do: by BIC and held out over `fold`), then read
// again against what the simulator gives for them together: the terms are simulated at their
// fitted values (SimulateSelection), the difference from the model's own prediction there is
// taken off the data (GapModel::Shifted), and they are refitted; `rounds` times. The model adds
// the terms' departures, simulated one at a time, and moves the window once for all; where
// their joint response is not that sum (an offset beside a drift near the depth where the
// window outgrows the panel), the first fit reads the sizes off it. `runs` gains the
// simulations of the table made. On a failed simulation or refit, the last fit; `done` (when
// given) the rounds completed.
ModelFit SimulatedBeside(const GapModel& model, const ModelFit& fit, const TermFit& beside,
                         const std::vector<char>& train, const std::vector<int>& fold,
                         int num_folds, const sim::SimParams& base,
                         const SimulateOptions& options, int rounds, int* runs,
                         int* done = nullptr);

// The selection's effects and calibration as the simulator takes them, one set per scenario of
// the design.
std::vector<sim::SimParams> SelectedParams(const Simulations& sims, const sim::SimParams& base,
                                           const ModelFit& fit, const Design& design);

}  // namespace depthbias::gap
