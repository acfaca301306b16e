#pragma once
// Fitting scenarios with their margins (margin.h): the bias fit, weighted by 1/σ²(Z), alternates
// with the residual model fitted to the held-out errors the weighted fit makes:
//
//   w ← prior weights (1, or the valid pixel counts)
//   repeat `rounds` times:
//     per scenario: θ ← Fit(samples, w);  e_i ← guarded held-out error of row i
//                   (leave one test point out, same weights)
//     (σ_place per scenario, c) ← FitResidualModel(e², Z)   (c shared when pooled)
//     w_i ← prior_i / σ²(Z_i), normalized to mean 1
//   θ ← Fit(samples, w); covariance by the sandwich Σ = C·(Σ w_i² σ²(Z_i) g_i g_iᵀ)·C
//
// Held-out errors, not in-sample residuals, feed the residual model: they are what a reading of
// a test point the fit has not seen is off by, and what the margin is for. Weighting by 1/σ²(Z)
// makes the near rows, whose scatter is small, count for what they are worth: the far rows'
// scatter no longer moves near corrections.

#include <vector>

#include "model/cv.h"
#include "model/fit.h"
#include "model/margin.h"

namespace depthbias::model {

struct JointFitResult {
  bool success = false;
  std::string message;               // the first scenario that failed and why
  std::vector<FitResult> fits;       // per scenario, with residual model and guard
  std::vector<ResidualData> errors;  // per scenario: depths and squared held-out errors
  ResidualFitResult residual;        // the last residual model fit (fixed scenarios last)
  // Scenarios whose residual model fell back to in-sample residuals (a test point could not be
  // left out), each with why; FitResult::margin_in_sample says it per scenario too.
  std::vector<std::string> warnings;
};

// Fits the scenarios together (their noise coefficient pooled when params.margins.residual.
// pool_noise). `fixed` are other scenarios' errors that take part in the residual model as they
// are (cross-validating one scenario keeps the others' fixed). With margins disabled, each
// scenario is a plain Fit. Never throws for bad data.
JointFitResult FitWithMargins(const std::vector<std::vector<Sample>>& scenarios,
                              const FitParams& params,
                              const std::vector<ResidualData>& fixed = {});

// Cross-validation of the whole procedure on one scenario: each fold refits it with its margin
// (the other scenarios' errors `fixed`), and predicts the held-out rows' guarded bias and
// predictive σ (CvResult::std_m).
CvResult CrossValidateWithMargins(const std::vector<Sample>& samples, const FitParams& params,
                                  CvScheme scheme, const std::vector<ResidualData>& fixed = {});

}  // namespace depthbias::model
