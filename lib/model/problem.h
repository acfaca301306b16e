#pragma once
// Builds the Ceres problem of a bias fit: one BiasResidual per sample (with the robust loss),
// one PriorResidual per parameter whose prior strength is positive.

#include <vector>

#include <ceres/problem.h>

#include "model/fit.h"

namespace depthbias::model {

// Prior (mean, strength) of each parameter of `form` under `params`: the form's neutral mean,
// strength params.lambda for penalized parameters and 0 for free ones, then the overrides.
// Throws std::invalid_argument for an override naming no parameter of the form.
std::vector<std::pair<double, double>> PriorsFor(const Form& form, const FitParams& params);

// Robust loss for the data residuals (nullptr = plain squares). Ceres takes ownership.
ceres::LossFunction* MakeLoss(Loss loss, const std::string& model, double scale_m);

// `theta` (num_params values) must outlive the problem; so must `form`.
void BuildProblem(const Form& form, const std::vector<Sample>& samples, const FitParams& params,
                  double* theta, ceres::Problem* problem);

}  // namespace depthbias::model
