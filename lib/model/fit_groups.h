#pragma once
// The fit_bias pipeline: group the rows into scenarios, fit each, cross-validate each, and
// gather what the weights YAML holds.

#include <string>
#include <vector>

#include "records/bias_weights.h"
#include "records/panel_metrics.h"
#include "model/cv.h"
#include "model/fit.h"
#include "model/samples.h"

namespace depthbias::model {

struct FitGroupsParams {
  FitParams fit;
  std::vector<std::string> group_by = {"light", "preset"};  // DESIGN.md: per (light, preset)
  // First = primary. Leaving an angle out checks what a per-angle parameter hides in-sample.
  std::vector<CvScheme> cv = {CvScheme::kPoint, CvScheme::kDistance, CvScheme::kAngle};
  // When not empty: also estimate, with the primary scheme, the held-out error of choosing
  // among these candidates by inner cross-validation (NestedCrossValidate), so that the choice
  // of a model is itself judged out of sample.
  std::vector<FitParams> nested_candidates;
  // When not empty, the point fit is chosen among these (select.h: pooled held-out RMSE in
  // metres, leave one test point out) and fit.model is not used; every cross-validation then
  // makes the choice again inside each fold.
  std::vector<FitParams> select;

  bool IsValid(std::string* why) const;
};

struct GroupReport {
  Group group;
  std::vector<Sample> samples;  // the group's rows as fitted (the cross-validations' order)
  FitResult fit;
  std::vector<CvResult> cv;  // as FitGroupsParams::cv, kNone left out
  CvResult nested;           // when nested_candidates were given
  std::vector<int> nested_chosen;  // candidate chosen in each outer fold
  // The unit's disparity noise σ_d in this scenario (GroupDisparityNoise).
  records::BiasDisparityNoise disparity_noise;
};

struct FitReport {
  bool success = false;
  std::string message;       // the first group that failed and why
  std::vector<std::string> warnings;  // cross-validations that could not run (fit still done)
  std::vector<GroupReport> groups;
  FitParams fitted;          // the point fit's parameters (the candidate chosen, if any)
  int chosen = -1;           // index into FitGroupsParams::select, when a choice was made
  std::vector<std::string> candidate_labels;  // "form/loss" of every candidate
  std::vector<double> candidate_rmse_m;       // its pooled held-out RMSE (leave a point out)
  int rows_used = 0;
  int rows_skipped = 0;      // rows whose status is not "ok" (failed measurements)
  double seconds = 0.0;      // wall time of fits and cross-validation
};

// Fits every group; fails (success = false) if there is no "ok" row or any group's fit fails.
// A cross-validation the design cannot support (e.g. leave-one-distance-out with two
// distances) does not fail the run: its result says why and a warning names it.
FitReport FitGroups(const std::vector<records::PanelMetrics>& rows, const FitGroupsParams& params);

// σ_d of a group's scenario: the median (the mean of the two middle values for an even count)
// of its rows' sigma_d_px where they measured it (finite, > 0), with how many. Not known when no
// row measured it, or when the group pools presets (preset "*": σ_d is a preset's, DESIGN.md).
records::BiasDisparityNoise GroupDisparityNoise(const std::vector<records::PanelMetrics>& rows,
                                               const Group& group);

// Every form × {none, huber} with the fit's other settings: the candidates of a nested check.
std::vector<FitParams> DefaultCandidates(const FitParams& base);

// A plain-text table of the report: per group n, in-sample and cross-validated RMSE / MAE,
// the nested estimate if any, and the weights.
std::string FormatFitTable(const FitReport& report, const FitGroupsParams& params);

// Coverage of the safe distance out of sample, per nominal distance: the share of held-out rows
// whose truth lies below corrected − k·σ (the dangerous side), from one scheme's
// cross-validation (CrossValidateWithMargins: each row predicted by a fit that did not see its
// test point, its distance or its angle). With a normal error, k = 2 promises at most 2.3 % beyond.
struct CoverageRow {
  double distance_m = 0.0;
  int n = 0;                        // rows, every group
  int beyond = 0;                   // truth < corrected − k·σ
  double mean_error_m = 0.0;        // mean of corrected − truth (+: reads farther than truth)
  double mean_std_m = 0.0;          // mean held-out σ
  double rms_z = 0.0;               // √mean((corrected − truth)/σ)²: 1 when σ is the right size
  // P(X ≥ beyond) for X ~ Binomial(n, Φ(−k)): how likely so many misses are if the margin keeps
  // exactly the normal promise (small: the margin is too narrow at this distance).
  double promise_p = 1.0;
  std::vector<int> group_n, group_beyond;  // per group, in report order
  std::vector<double> group_mean_error_m;
};
// `scheme` indexes the cross-validations run (FitGroupsParams::cv without kNone; 0 = primary).
std::vector<CoverageRow> Coverage(const FitReport& report, double k, size_t scheme = 0);
// One table per cross-validation run, each headed by its scheme.
std::string FormatCoverageTable(const FitReport& report, double k);
std::string FormatCoverageTable(const FitReport& report, double k, size_t scheme);

// The weights record of a successful report (provenance left empty for the caller).
records::BiasWeights ToWeights(const FitReport& report, const FitGroupsParams& params);

}  // namespace depthbias::model
