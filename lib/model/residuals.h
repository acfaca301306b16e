#pragma once
// Ceres residuals of the bias fit, each testable alone:
//  - BiasResidual: r = √w · (b(θ; Z, α) − target), one per sample [m];
//  - PriorResidual: r = √λ_j · (θ_j − μ_j), the L2 (Tikhonov) prior of one parameter.
// Summed as ½Σr², they give ½(Σ w·(b − y)² + Σ λ_j (θ_j − μ_j)²): with μ = 0 and the intercept
// free this is scikit-learn's Ridge objective ||y − Xw − b||² + λ||w||² (up to the factor ½).

#include <cmath>
#include <vector>

#include <ceres/cost_function.h>

#include "model/forms.h"

namespace depthbias::model {

class BiasResidual : public ceres::CostFunction {
 public:
  // `form` must outlive the residual.
  BiasResidual(const Form& form, const Features& x, double target_m, double weight)
      : form_(form), x_(x), target_m_(target_m), sqrt_w_(std::sqrt(weight)) {
    set_num_residuals(1);
    mutable_parameter_block_sizes()->push_back(form.num_params());
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double* theta = parameters[0];
    const double b = form_.Bias(theta, x_);
    if (!std::isfinite(b)) return false;
    residuals[0] = sqrt_w_ * (b - target_m_);
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      const std::vector<double> g = form_.BiasGradient(theta, x_);
      for (size_t j = 0; j < g.size(); ++j) jacobians[0][j] = sqrt_w_ * g[j];
    }
    return true;
  }

 private:
  const Form& form_;
  Features x_;
  double target_m_;
  double sqrt_w_;
};

class PriorResidual : public ceres::CostFunction {
 public:
  PriorResidual(int num_params, int index, double mean, double strength)
      : index_(index), mean_(mean), sqrt_strength_(std::sqrt(strength)) {
    set_num_residuals(1);
    mutable_parameter_block_sizes()->push_back(num_params);
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    residuals[0] = sqrt_strength_ * (parameters[0][index_] - mean_);
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      const int n = parameter_block_sizes()[0];
      for (int j = 0; j < n; ++j) jacobians[0][j] = j == index_ ? sqrt_strength_ : 0.0;
    }
    return true;
  }

 private:
  int index_;
  double mean_;
  double sqrt_strength_;
};

}  // namespace depthbias::model
