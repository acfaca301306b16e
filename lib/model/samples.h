#pragma once
// From panel-metrics rows to fit samples, and rows into scenario groups.

#include <cmath>
#include <string>
#include <vector>

#include "records/panel_metrics.h"
#include "model/forms.h"

namespace depthbias::model {

// One recording as the fit sees it. DESIGN.md: target bias = measured median − nominal
// distance, Z = the measured median, α = the nominal angle.
struct Sample {
  Features x;
  double target_m = 0.0;    // median_m − distance_m
  double weight = 1.0;      // multiplies the squared residual
  double distance_m = 0.0;  // nominal distance (the test point's key, with angle_deg)
  double angle_deg = 0.0;   // nominal angle, unsigned (|angle_deg| of the row)
  size_t row = 0;           // index into the rows it came from
};

// Samples of the rows listed (rows whose status is not "ok" must not be listed). With
// weight_by_valid_pixels, each weight is the row's valid pixel count (valid_pct × region_px ×
// frames, or valid_pct × frames where region_px is unknown) over the group's mean count, so
// that the weights average 1.
std::vector<Sample> MakeSamples(const std::vector<records::PanelMetrics>& rows,
                                const std::vector<size_t>& which, bool weight_by_valid_pixels);

// A scenario: the rows sharing the grouping keys' values.
struct Group {
  std::string light = "*";    // "*" where light is not a grouping key
  std::string preset = "*";
  std::string emitter = "*";
  std::vector<size_t> rows;   // indices of rows UsableForFit
  std::string Label() const;  // "daylight/HA"
};

// A row can be fitted when it was measured ("ok") and has its ground truth (distance, angle).
inline bool UsableForFit(const records::PanelMetrics& r) {
  return r.ok() && std::isfinite(r.distance_m) && std::isfinite(r.angle_deg);
}

// Keys allowed: light, preset, emitter (any subset, none = one group). Throws
// std::invalid_argument naming an unknown key. Rows that are not UsableForFit are left out.
// Groups come out sorted by their keys.
std::vector<Group> GroupRows(const std::vector<records::PanelMetrics>& rows,
                             const std::vector<std::string>& group_by);

// Distinct values (to 1e-9) of distance_m / angle_deg in samples, ascending.
std::vector<double> DistinctDistances(const std::vector<Sample>& samples);
std::vector<double> DistinctAngles(const std::vector<Sample>& samples);

}  // namespace depthbias::model
