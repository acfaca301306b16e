#pragma once
// Calibration of the base sensor model to a real metrics table: per scenario (light × preset),
// the disparity noise σ_d and the hole probability p are fitted by Ceres so that the metrics-only
// simulation of every real recording's cell matches its plane_std_m and valid_pct.
//
// Residuals per recording: log(sim plane_std / real plane_std) (relative, since plane_std spans
// a decade) and (sim valid_pct − real valid_pct) / valid_scale_pct. Parameters: log σ_d and
// logit p, so both stay in range. Derivatives by central differences of the simulation itself,
// which is smooth in (σ_d, p) because the random draws are fixed per recording.

#include <string>
#include <vector>

#include "records/panel_metrics.h"
#include "sim/sim_metrics.h"
#include "sim/stereo_sim.h"

namespace depthbias::gap {

struct CalibrateParams {
  int frames = 10;                 // simulated frames per recording while fitting
  double valid_scale_pct = 10.0;   // valid_pct residual scale [percentage points]
  int max_iterations = 50;
  double relative_step = 0.05;     // central-difference step on log σ_d and logit p
  // Upper bound on σ_d. Beyond it the simulated panel at 16 m is a cloud deeper than it is wide
  // (σ_Z = Z²·σ_d/(f·B) > 0.6 m): the plane fit turns sideways and plane_std saturates near the
  // panel's own extent, a degenerate optimum that flat real plane_std values would pull towards.
  double max_sigma_d_px = 0.15;
  sim::MetricsParams metrics;

  bool IsValid(std::string* why) const;
};

// One real recording beside its simulation after the fit.
struct CalibrationCell {
  std::string bag;
  std::string emitter;
  double distance_m = 0;
  double angle_deg = 0;
  double real_plane_std_m = 0;
  double sim_plane_std_m = 0;
  double real_valid_pct = 0;
  double sim_valid_pct = 0;
};

struct ScenarioFit {
  sim::ScenarioParams initial;
  sim::ScenarioParams fitted;
  int recordings = 0;             // rows used
  bool converged = false;
  int iterations = 0;
  double initial_cost = 0;
  double final_cost = 0;
  double rms_log_plane_std = 0;   // RMS of log(sim/real) plane_std after the fit
  double rms_valid_pct = 0;       // RMS of sim − real valid_pct [points] after the fit
  double mean_real_plane_std_m = 0, mean_sim_plane_std_m = 0;
  double mean_real_valid_pct = 0, mean_sim_valid_pct = 0;
  std::string report;             // Ceres' BriefReport()
  std::vector<CalibrationCell> cells;
};

struct CalibrationResult {
  bool success = false;
  std::string message;            // why not, or notes (rows skipped)
  sim::SensorParams sensor;            // the input sensor with the fitted scenarios
  std::vector<ScenarioFit> scenarios;
  int rows_used = 0;
  int rows_skipped = 0;
};

// Fits every (light, preset) the real table holds. The protocol's scene and distance meaning,
// the effects and the seed in params are used as given; params.sensor's scenarios are the start.
CalibrationResult CalibrateSensor(const sim::SimParams& params,
                                  const std::vector<records::PanelMetrics>& real,
                                  const CalibrateParams& calibrate = {});

// The fit as a plain table: one line per recording (real and simulated plane_std and
// valid_pct), then one per scenario (fitted values, means, RMS misfit, Ceres' brief report).
std::string FormatCalibration(const CalibrationResult& result);

// The fit as YAML (a top-level calibration: block) for the sensor file's record.
std::string CalibrationYaml(const CalibrationResult& result, const std::string& source);

}  // namespace depthbias::gap
