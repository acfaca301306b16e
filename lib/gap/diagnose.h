#pragma once
// The sim-to-real gap diagnosis (DESIGN.md, "The sim-to-real gap"): where a real metrics table
// departs from the base simulator, which registered effect explains it, and how far the gap
// shrinks once that effect is added, in sample and on held-out cells.
//
//  1. Gap: z = (real − sim) / noise per cell and compared metric, the base sensor as configured
//     (noise from emitter on/off replicates, noise.h).
//  2. Where: shares of Σz² by factor and pair of factors, by metric, and the significant cells
//     (localize.h).
//  3. Which: the calibrated base (the sensor's σ_d and hole probability per scenario moved within
//     their prior, fit.h) is the reference; every candidate is fitted alone with it, its
//     parameters shared or one set per scenario (the better by BIC), ranked by
//     ΔBIC = D(reference) − D(effect) − k·ln n and by its held-out gain (the reference's held-out
//     deviance minus its own); each metric's dispersion φ (≥ 1: how much wider than the
//     replicates' noise its residuals about the reference are) puts the metrics on one footing.
//     Forward selection then adds the effect of largest ΔBIC while it earns both ΔBIC > 0 and a
//     held-out gain > 0 (φ re-estimated about the current model at every step). Signatures
//     (each effect's change of the metrics at a typical size, in noise units, the calibration's
//     directions projected out) are compared pairwise: |r| ≥ confounded_r is reported as
//     confounded, and an effect confounded with one already selected is not added.
//  4. How far: the gap of the selected effects in sample and held out (leave one distance out by
//     default), and the selected effects simulated at their fitted values (verification).
//  5. What is left: the cells still significant after the selected effects.

#include <string>
#include <vector>

#include "gap/candidates.h"
#include "gap/design.h"
#include "gap/fit.h"
#include "gap/localize.h"
#include "gap/noise.h"
#include "gap/simulations.h"
#include "records/panel_metrics.h"
#include "sim/stereo_sim.h"

namespace depthbias::gap {

struct DiagnoseParams {
  std::string candidates = "all";  // "all" or registry names, comma-separated
  Holdout holdout;                 // leave one distance out
  SimulateOptions simulate;        // 10 frames a cell
  FitSettings fit;
  double confounded_r = 0.95;  // |signature correlation| at which two effects are confounded
  // Correlation of a signature with one calibration direction (σ_d or hole probability of every
  // scenario) at which the effect is taken for that recalibration: reported as confounded with
  // it, and fitted with that direction held at the configured sensor.
  double absorb_r = 0.9;
  double alpha = 0.05;         // significance of a cell's gap (Bonferroni over the cells)
  int max_selected = 4;        // effects forward selection may add
  bool verify = true;          // simulate the selected effects at their fitted values

  bool IsValid(std::string* why) const;
};

// The gap of a model over a set of cells: mean squared scaled gap (1 ≈ replicate noise).
struct GapStat {
  std::vector<double> mean_sq;  // per compared metric
  std::vector<int> n;           // observations per metric
  double overall = 0;           // Σz² / n over every metric
  int count = 0;
};

struct EffectResult {
  std::string name;
  bool per_scenario = false;        // the version kept (better ΔBIC)
  TermFit fit;
  double delta_bic = 0;             // of the version kept, against the calibrated base
  double delta_bic_shared = 0, delta_bic_per_scenario = 0;
  double heldout_gain = 0;          // held-out deviance of the calibrated base minus its own
  GapStat in_sample, heldout;
  double shrink_in_sample_pct = 0;  // of the baseline gap (base sensor as configured)
  double shrink_heldout_pct = 0;
  bool earns = false;               // ΔBIC > 0 and held-out gain > 0 alone
  std::vector<double> signature;    // [obs] in noise units, calibration projected out
};

struct Confounded {
  // Two effects, or an effect and "calibration:sigma_d" / "calibration:hole_prob".
  std::string a, b;
  double correlation = 0;
};

struct SelectionStep {
  std::string effect;
  bool per_scenario = false;
  double delta_bic = 0;
  double heldout_gain = 0;
};

struct DiagnoseResult {
  bool success = false;
  std::string message;
  Design design;
  std::vector<Candidate> candidates;      // in the simulations' order (Term::candidate)
  std::vector<std::string> metric_names;  // the compared metrics
  std::string holdout;
  int folds = 0;
  NoiseEstimate noise;
  int simulations = 0;           // simulations of the whole table
  std::vector<double> sim_base;  // [obs] the base simulation of every cell
  std::vector<double> z_base;    // [obs] baseline scaled gap
  GapStat baseline, baseline_heldout;
  Localization localization;
  std::vector<sim::ScenarioParams> configured, calibrated;  // per scenario
  ModelFit calibration;           // the calibrated base (reference)
  GapStat calibration_in, calibration_heldout;
  std::vector<double> dispersion;  // per compared metric, about the calibrated base
  std::vector<EffectResult> effects;  // every candidate alone, best ΔBIC first
  std::vector<Confounded> confounded;
  std::vector<Confounded> correlations;  // every pair of effects' signature correlation
  std::vector<SelectionStep> steps;
  ModelFit selected;               // the selected effects fitted together (additively)
  std::vector<double> z_selected, z_selected_heldout;
  GapStat selected_in, selected_heldout;
  bool verified = false;           // the selected effects were simulated
  std::vector<double> z_verified;
  GapStat verified_in;
  std::vector<CellGap> remaining;  // cells still significant after the selected effects

  // The result of the named effect alone (nullptr if it was not a candidate).
  const EffectResult* Effect(const std::string& name) const;
  bool Selected(const std::string& name) const;
  bool ConfoundedWith(const std::string& a, const std::string& b) const;
};

// A real table diagnosed against the simulator with `base` (protocol scene and distance meaning,
// sensor, seed; its departures are the base model's). Never throws for bad data: success false
// and message say why.
DiagnoseResult Diagnose(const std::vector<records::PanelMetrics>& real,
                        const sim::SimParams& base, const DiagnoseParams& params);

// The same with the simulations made beforehand (SimulateDesign on a design of the same cells,
// e.g. one set for several tables of one protocol).
DiagnoseResult DiagnoseWith(const Design& design, const Simulations& sims,
                            const sim::SimParams& base, const DiagnoseParams& params);

// The effects as the simulator takes them, from a fitted term at group g.
sim::EffectSpec EffectOf(const Simulations& sims, const TermFit& term, int group);

}  // namespace depthbias::gap
