#include "model/problem.h"

#include <stdexcept>

#include <ceres/loss_function.h>

#include "model/residuals.h"

namespace depthbias::model {

std::vector<std::pair<double, double>> PriorsFor(const Form& form, const FitParams& params) {
  std::vector<std::pair<double, double>> priors;
  for (const auto& p : form.params()) {
    priors.emplace_back(p.prior_mean, p.penalized ? params.lambda : 0.0);
  }
  for (const auto& o : params.priors) {
    bool found = false;
    for (size_t j = 0; j < form.params().size(); ++j) {
      if (form.params()[j].name == o.name) {
        priors[j] = {o.mean, o.strength};
        found = true;
      }
    }
    if (!found) {
      throw std::invalid_argument("prior for '" + o.name + "': model " + form.name() +
                                  " has no such parameter");
    }
  }
  return priors;
}

ceres::LossFunction* MakeLoss(Loss loss, const std::string& model, double scale_m) {
  switch (ResolveLoss(loss, model)) {
    case Loss::kHuber: return new ceres::HuberLoss(scale_m);
    case Loss::kCauchy: return new ceres::CauchyLoss(scale_m);
    case Loss::kSoftL1: return new ceres::SoftLOneLoss(scale_m);
    default: return nullptr;
  }
}

void BuildProblem(const Form& form, const std::vector<Sample>& samples, const FitParams& params,
                  double* theta, ceres::Problem* problem) {
  const int n = form.num_params();
  for (const auto& s : samples) {
    // The robust loss acts on √w·r, so its scale is in metres at weight 1.
    problem->AddResidualBlock(new BiasResidual(form, s.x, s.target_m, s.weight),
                              MakeLoss(params.loss, form.name(), params.loss_scale_m), theta);
  }
  const auto priors = PriorsFor(form, params);
  for (int j = 0; j < n; ++j) {
    const auto [mean, strength] = priors[static_cast<size_t>(j)];
    if (strength > 0.0) {
      problem->AddResidualBlock(new PriorResidual(n, j, mean, strength), nullptr, theta);
    }
  }
  if (problem->NumResidualBlocks() == 0) problem->AddParameterBlock(theta, n);
}

}  // namespace depthbias::model
