#pragma once
// The fit_bias pipeline: group the rows into scenarios, fit each, cross-validate each, and
// gather what the weights YAML holds.

#include <string>
#include <vector>

#include "camera/bias_weights.h"
#include "camera/panel_metrics.h"
#include "model/cv.h"
#include "model/fit.h"
#include "model/samples.h"

namespace depthbias::model {

struct FitGroupsParams {
  FitParams fit;
  std::vector<std::string> group_by = {"light", "preset"};  // DESIGN.md: per (light, preset)
  std::vector<CvScheme> cv = {CvScheme::kPoint, CvScheme::kDistance};  // first = primary

  bool IsValid(std::string* why) const;
};

struct GroupReport {
  Group group;
  FitResult fit;
  std::vector<CvResult> cv;  // as FitGroupsParams::cv, kNone left out
};

struct FitReport {
  bool success = false;
  std::string message;       // the first group that failed and why
  std::vector<GroupReport> groups;
  int rows_used = 0;
  int rows_skipped = 0;      // rows whose status is not "ok"
  double seconds = 0.0;      // wall time of fits and cross-validation
};

// Fits every group; fails (success = false) if there is no "ok" row or any group fails.
FitReport FitGroups(const std::vector<camera::PanelMetrics>& rows, const FitGroupsParams& params);

// The weights record of a successful report (provenance left empty for the caller).
camera::BiasWeights ToWeights(const FitReport& report, const FitGroupsParams& params);

}  // namespace depthbias::model
