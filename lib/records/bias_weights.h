#pragma once
// The record of a fitted bias model, as the weights YAML holds it (DESIGN.md "File formats"):
// a plain value type shared by model (which fits and evaluates it) and io (which reads and
// writes it), so that neither depends on the other.

#include <string>
#include <vector>

namespace depthbias::records {

struct BiasCrossValidation {
  std::string scheme;   // "point" (leave one test point out), "distance", or "none"
  double rmse_m = 0.0;  // of the held-out bias predictions
  double mae_m = 0.0;
};

// The residual model of a scenario (model/margin.h): σ²(Z) = σ_place² + (c·Z²)², fitted to the
// held-out errors.
struct BiasMargin {
  bool known = false;        // false: weights of schema 1, which hold only residual_std_m
  double placement_m = 0.0;  // σ_place [m]
  double noise_per_m = 0.0;  // c [1/m]
  bool weighted = false;     // the bias fit was weighted by 1/σ²(Z)
  // What σ was fitted to: "held_out" (each row predicted by a fit that left its test point
  // out) or "in_sample" (a test point could not be left out: residuals scaled by n/(n − p), a
  // weaker margin).
  std::string errors = "held_out";
};

// The unit's temporal disparity noise σ_d in a scenario: the median of its recordings'
// sigma_d_px (the metrics CSV), the reading noise of the obstacle detector's margin.
struct BiasDisparityNoise {
  bool known = false;    // false: the rows did not measure it (or weights from before it)
  double sigma_px = 0.0;  // σ_d [px], > 0
  int recordings = 0;     // rows whose sigma_d_px the median is of
};

// One fitted scenario (a group of rows, e.g. one light and preset).
struct BiasWeightsGroup {
  std::string light;   // the group's light, or "*" when light is not a grouping key
  std::string preset;  // the group's preset, or "*"
  std::string emitter = "*";  // the group's emitter when it is a grouping key, else "*"
  int n = 0;           // rows fitted
  std::vector<std::string> names;       // parameter names in the model's order
  std::vector<double> values;           // fitted values, same order
  std::vector<double> knots_deg;        // off-axis knots of knot-based forms, else empty
  double rmse_m = 0.0;                  // in-sample
  double mae_m = 0.0;
  double residual_std_m = 0.0;          // sqrt(RSS / (n − p)): the unexplained scatter
  std::vector<BiasCrossValidation> cv;  // one entry per scheme run
  std::vector<std::vector<double>> covariance;  // of values, names × names; empty if unknown
  BiasMargin margin;
  BiasDisparityNoise disparity_noise;  // written only for a group of one preset
};

struct BiasWeights {
  std::string schema = "depthbias.weights/2";
  std::string model;   // "paper6", "disp_scale", ...
  std::string target = "median_m - distance_m";  // what the bias means
  double lambda = 0.0;  // default prior strength of the fit
  std::string loss = "none";
  double loss_scale_m = 1.0;
  double focal_px = 0.0;    // constants of disparity-space forms
  double baseline_m = 0.0;
  std::vector<std::string> group_by;  // e.g. {"light", "preset"}
  // Near guard (model/margin.h): below near_m a correction that would move a reading farther is
  // not applied, blended in up to full_m [m]; both 0: off.
  double near_m = 0.0;
  double full_m = 0.0;
  bool noise_pooled = false;  // one noise coefficient c for every group
  std::vector<BiasWeightsGroup> groups;
  // Provenance.
  std::string input_file;
  std::string input_sha256;
  std::string tool;
  std::string tool_version;
};

}  // namespace depthbias::records
