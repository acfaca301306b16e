#include "model/margin.h"

#include <algorithm>
#include <cmath>

#include <ceres/gradient_problem.h>
#include <ceres/gradient_problem_solver.h>

namespace depthbias::model {
namespace {

bool Fail(std::string* why, const std::string& message) {
  if (why) *why = message;
  return false;
}

// Parameters: a_g (per scenario) and b (shared) or b_g, with σ_place = floor + e^a and
// c = floor + e^b, so that the floors hold without bounds.
class NegativeLogLikelihood : public ceres::FirstOrderFunction {
 public:
  NegativeLogLikelihood(const std::vector<ResidualData>& data, const ResidualFitParams& p)
      : data_(data), p_(p), groups_(static_cast<int>(data.size())) {}

  int NumParameters() const override { return groups_ + (p_.pool_noise ? 1 : groups_); }

  int NoiseIndex(int g) const { return groups_ + (p_.pool_noise ? 0 : g); }

  bool Evaluate(const double* x, double* cost, double* gradient) const override {
    *cost = 0.0;
    if (gradient) std::fill(gradient, gradient + NumParameters(), 0.0);
    for (int g = 0; g < groups_; ++g) {
      const double ea = std::exp(x[g]), eb = std::exp(x[NoiseIndex(g)]);
      const double sp = p_.min_placement_m + ea, c = p_.min_noise_per_m + eb;
      const ResidualData& d = data_[static_cast<size_t>(g)];
      for (size_t i = 0; i < d.depth_m.size(); ++i) {
        const double z2 = d.depth_m[i] * d.depth_m[i];
        const double v = sp * sp + c * c * z2 * z2;
        const double e2 = d.error2_m2[i];
        *cost += 0.5 * (e2 / v + std::log(v));  // ½ of −2 ln L, up to a constant
        if (gradient) {
          const double dv = 0.5 * (1.0 / v - e2 / (v * v));
          gradient[g] += dv * 2.0 * sp * ea;
          gradient[NoiseIndex(g)] += dv * 2.0 * c * z2 * z2 * eb;
        }
      }
    }
    return std::isfinite(*cost);
  }

 private:
  const std::vector<ResidualData>& data_;
  ResidualFitParams p_;
  int groups_;
};

}  // namespace

bool NearGuard::IsValid(std::string* why) const {
  if (!(near_m >= 0.0) || !(full_m >= near_m) || !std::isfinite(full_m)) {
    return Fail(why, "near guard: need 0 <= near_m <= full_m (both 0: off)");
  }
  return true;
}

double NearGuard::Share(double raw_range_m) const {
  if (!enabled() || raw_range_m >= full_m) return 1.0;
  if (raw_range_m <= near_m) return 0.0;
  return (raw_range_m - near_m) / (full_m - near_m);
}

double NearGuard::Apply(double corrected_m, double raw_m, double* share) const {
  const double s = corrected_m > raw_m ? Share(raw_m) : 1.0;
  if (share) *share = s;
  return raw_m + s * (corrected_m - raw_m);
}

bool ResidualFitParams::IsValid(std::string* why) const {
  if (!(min_placement_m > 0.0) || !(min_noise_per_m > 0.0)) {
    return Fail(why, "residual model floors must be > 0");
  }
  if (max_iterations < 1) return Fail(why, "residual model: max_iterations must be >= 1");
  return true;
}

ResidualFitResult FitResidualModel(const std::vector<ResidualData>& scenarios,
                                   const ResidualFitParams& params) {
  ResidualFitResult r;
  std::string why;
  if (!params.IsValid(&why)) {
    r.message = why;
    return r;
  }
  if (scenarios.empty()) {
    r.message = "residual model: no scenario";
    return r;
  }
  for (size_t g = 0; g < scenarios.size(); ++g) {
    const auto& d = scenarios[g];
    if (d.depth_m.empty() || d.depth_m.size() != d.error2_m2.size()) {
      r.message = "residual model: scenario " + std::to_string(g) + " has no errors";
      return r;
    }
    for (size_t i = 0; i < d.depth_m.size(); ++i) {
      if (!std::isfinite(d.depth_m[i]) || !(d.depth_m[i] > 0.0) ||
          !std::isfinite(d.error2_m2[i]) || d.error2_m2[i] < 0.0) {
        r.message = "residual model: non-finite depth or error";
        return r;
      }
    }
  }
  const int groups = static_cast<int>(scenarios.size());
  auto* nll = new NegativeLogLikelihood(scenarios, params);
  std::vector<double> x(static_cast<size_t>(nll->NumParameters()));
  // Start: the whole RMS error as placement, a disparity scatter of 0.05 px at f·B = 60.8 px·m.
  for (int g = 0; g < groups; ++g) {
    double s2 = 0.0;
    for (double e2 : scenarios[static_cast<size_t>(g)].error2_m2) s2 += e2;
    s2 /= static_cast<double>(scenarios[static_cast<size_t>(g)].error2_m2.size());
    x[static_cast<size_t>(g)] = std::log(std::max(std::sqrt(s2), 2 * params.min_placement_m));
  }
  for (size_t j = static_cast<size_t>(groups); j < x.size(); ++j) x[j] = std::log(0.05 / 60.8);
  ceres::GradientProblem problem(nll);
  ceres::GradientProblemSolver::Options options;
  options.max_num_iterations = params.max_iterations;
  options.logging_type = ceres::SILENT;
  options.function_tolerance = 1e-12;
  options.gradient_tolerance = 1e-10;
  ceres::GradientProblemSolver::Summary summary;
  ceres::Solve(options, problem, x.data(), &summary);
  r.solver_report = summary.BriefReport();
  r.iterations = static_cast<int>(summary.iterations.size());
  r.final_cost = summary.final_cost;
  if (!summary.IsSolutionUsable() || !std::isfinite(summary.final_cost)) {
    r.message = "residual model: the solver failed: " + summary.message;
    return r;
  }
  for (int g = 0; g < groups; ++g) {
    ResidualModel m;
    m.placement_m = params.min_placement_m + std::exp(x[static_cast<size_t>(g)]);
    m.noise_per_m = params.min_noise_per_m + std::exp(x[static_cast<size_t>(nll->NoiseIndex(g))]);
    m.known = std::isfinite(m.placement_m) && std::isfinite(m.noise_per_m);
    if (!m.known) {
      r.message = "residual model: the fit diverged";
      return r;
    }
    r.models.push_back(m);
  }
  r.success = true;
  return r;
}

}  // namespace depthbias::model
