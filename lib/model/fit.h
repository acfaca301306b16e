#pragma once
// Least-squares fit of one bias model form to one group's samples with Ceres: an L2 prior
// (mean and strength per parameter), an optional robust loss, optional per-sample weights,
// and the parameter covariance for predictive standard deviations.

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "camera/intrinsics.h"
#include "model/forms.h"
#include "model/samples.h"

namespace depthbias::model {

// kAuto: the form's own default — plain least squares for paper6 (the article's ridge), Huber
// for the disparity-space forms (a recording whose panel depth is off by more than the scale
// is a failed recording, not a trend to follow).
enum class Loss { kAuto, kNone, kHuber, kCauchy, kSoftL1 };
bool ParseLoss(const std::string& text, Loss* loss);
std::string LossName(Loss loss);
// kAuto resolved for a form.
Loss ResolveLoss(Loss loss, const std::string& model);

// Overrides the prior of one parameter by name.
struct PriorOverride {
  std::string name;
  double mean = 0.0;
  double strength = 0.0;  // λ_j [1/unit²·m²]; 0 = free
};

struct FitParams {
  std::string model = "disp_knots";  // one of FormNames()
  double lambda = 0.001;   // prior strength of every penalized parameter [m²/unit²]
  Loss loss = Loss::kAuto;
  double loss_scale_m = 1.0;  // where the robust loss departs from the square [m]
  bool weight_by_valid_pixels = false;
  double focal_px = camera::D455::kFocalPx;    // f of disparity-space forms
  double baseline_m = camera::D455::kBaselineM;  // B of disparity-space forms
  std::vector<PriorOverride> priors;
  int max_iterations = 200;
  bool compute_covariance = true;

  bool IsValid(std::string* why) const;
};

struct FitResult {
  bool success = false;
  std::string message;  // why not, when !success
  std::string model;
  FormConstants constants;
  std::shared_ptr<const Form> form;  // the form fitted (knots included)
  std::vector<std::string> names;  // parameter names, the form's order
  std::vector<std::string> units;
  std::vector<double> values;
  int n = 0;                     // samples fitted
  std::vector<double> residuals_m;  // b(θ̂; x_i) − target_i, per sample
  double rmse_m = 0.0;          // in-sample, unweighted
  double mae_m = 0.0;
  double residual_std_m = 0.0;  // sqrt(Σ w r² / (n − p)); NaN if n ≤ p
  bool covariance_ok = false;
  Eigen::MatrixXd covariance;   // of values (σ²-scaled (JᵀJ)⁻¹, prior included)
  std::string solver_report;    // Ceres' BriefReport()
  int iterations = 0;
  double final_cost = 0.0;
};

// Checks the design against the form before fitting: n ≥ number of parameters, enough
// distinct distances and angles, finite values. Returns false with a reason.
bool CheckDesign(const Form& form, const std::vector<Sample>& samples, std::string* why);

// The form a fit of `params.model` on these samples uses (disp_knots takes its knots at the
// samples' distinct angles). Throws std::invalid_argument for an unknown model.
std::unique_ptr<Form> FormFor(const FitParams& params, const std::vector<Sample>& samples);

// Fits; never throws for bad data (success = false and message say why).
FitResult Fit(const std::vector<Sample>& samples, const FitParams& params);

// Predicted bias with a fitted result, and its predictive standard deviation
// sqrt(gᵀ Σ g + σ²) with g = ∂b/∂θ, Σ the covariance and σ the residual std.
double PredictBias(const FitResult& fit, const Features& x);
double PredictiveStd(const FitResult& fit, const Features& x);

}  // namespace depthbias::model
