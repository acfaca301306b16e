#include "model/fit.h"

#include <cmath>
#include <sstream>

#include <Eigen/SVD>
#include <ceres/covariance.h>
#include <ceres/solver.h>

#include "model/problem.h"

namespace depthbias::model {

bool ParseLoss(const std::string& text, Loss* loss) {
  if (text == "auto") *loss = Loss::kAuto;
  else if (text == "none" || text == "l2" || text == "squared") *loss = Loss::kNone;
  else if (text == "huber") *loss = Loss::kHuber;
  else if (text == "cauchy") *loss = Loss::kCauchy;
  else if (text == "soft_l1" || text == "soft-l1") *loss = Loss::kSoftL1;
  else return false;
  return true;
}

std::string LossName(Loss loss) {
  switch (loss) {
    case Loss::kAuto: return "auto";
    case Loss::kNone: return "none";
    case Loss::kHuber: return "huber";
    case Loss::kCauchy: return "cauchy";
    case Loss::kSoftL1: return "soft_l1";
  }
  return "none";
}

Loss ResolveLoss(Loss loss, const std::string& model) {
  if (loss != Loss::kAuto) return loss;
  return model == "paper6" ? Loss::kNone : Loss::kHuber;
}

bool MarginParams::Weighted(const std::string& model) const {
  if (!enabled || weighting == Weighting::kOff) return false;
  return weighting == Weighting::kOn || model != "paper6";
}

bool MarginParams::IsValid(std::string* why) const {
  if (!enabled) return true;
  if (rounds < 1) {
    if (why) *why = "margins: rounds must be >= 1";
    return false;
  }
  return residual.IsValid(why) && guard.IsValid(why);
}

bool FitParams::IsValid(std::string* why) const {
  auto fail = [why](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  bool known = false;
  for (const auto& n : FormNames()) known |= n == model;
  if (!known) {
    std::string names;
    for (const auto& n : FormNames()) names += (names.empty() ? "" : ", ") + n;
    return fail("unknown model '" + model + "' (known: " + names + ")");
  }
  if (!(lambda >= 0.0) || !std::isfinite(lambda)) return fail("lambda must be >= 0");
  if (!(loss_scale_m > 0.0) || !std::isfinite(loss_scale_m)) {
    return fail("loss_scale_m must be > 0");
  }
  if (!(focal_px > 0.0) || !(baseline_m > 0.0)) {
    return fail("focal_px and baseline_m must be > 0");
  }
  for (const auto& p : priors) {
    if (!(p.strength >= 0.0) || !std::isfinite(p.mean)) {
      return fail("prior for '" + p.name + "': strength must be >= 0 and mean finite");
    }
  }
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  return margins.IsValid(why);
}

bool CheckDesign(const Form& form, const std::vector<Sample>& samples, std::string* why) {
  const int n = static_cast<int>(samples.size());
  const int p = form.num_params();
  std::ostringstream msg;
  if (n < p) {
    msg << n << " points for " << p << " parameters of " << form.name();
    *why = msg.str();
    return false;
  }
  for (const auto& s : samples) {
    if (!std::isfinite(s.x.depth_m) || !(s.x.depth_m > 0.0) || !std::isfinite(s.target_m) ||
        !std::isfinite(s.x.angle_rad) || !std::isfinite(s.weight) || s.weight < 0.0) {
      msg << "row " << s.row << ": non-finite or non-positive depth, target, angle or weight";
      *why = msg.str();
      return false;
    }
  }
  const size_t distances = DistinctDistances(samples).size();
  const size_t angles = DistinctAngles(samples).size();
  if (static_cast<int>(distances) < form.min_distances() ||
      static_cast<int>(angles) < form.min_angles()) {
    msg << "singular design: " << distances << " distinct distance(s) and " << angles
        << " distinct angle(s); " << form.name() << " needs at least " << form.min_distances()
        << " and " << form.min_angles();
    *why = msg.str();
    return false;
  }
  return true;
}

std::unique_ptr<Form> FormFor(const FitParams& params, const std::vector<Sample>& samples) {
  FormConstants c;
  c.focal_px = params.focal_px;
  c.baseline_m = params.baseline_m;
  if (params.model == "disp_knots") c.knots_deg = DistinctAngles(samples);
  if (params.model == "disp_knots" && c.knots_deg.empty()) c.knots_deg = {0.0};
  return MakeForm(params.model, c);
}

FitResult Fit(const std::vector<Sample>& samples, const FitParams& params) {
  FitResult result;
  result.model = params.model;
  result.n = static_cast<int>(samples.size());
  std::string why;
  if (!params.IsValid(&why)) {
    result.message = why;
    return result;
  }
  std::shared_ptr<const Form> form;
  try {
    form = FormFor(params, samples);
  } catch (const std::invalid_argument& e) {
    result.message = e.what();
    return result;
  }
  result.form = form;
  result.constants = form->constants();
  for (const auto& p : form->params()) {
    result.names.push_back(p.name);
    result.units.push_back(p.unit);
    result.values.push_back(p.initial);
  }
  if (!CheckDesign(*form, samples, &why)) {
    result.message = why;
    return result;
  }
  const int p = form->num_params();
  // Identifiability from the data alone (the prior must not hide a degenerate design): the
  // data Jacobian at the start point must have full column rank.
  {
    Eigen::MatrixXd J(samples.size(), p);
    for (size_t i = 0; i < samples.size(); ++i) {
      const auto g = form->BiasGradient(result.values.data(), samples[i].x);
      for (int j = 0; j < p; ++j) J(static_cast<Eigen::Index>(i), j) = g[static_cast<size_t>(j)];
    }
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(J);
    const auto& sv = svd.singularValues();
    if (sv.size() == 0 || sv(sv.size() - 1) <= 1e-9 * sv(0)) {
      result.message = "singular design: the rows cannot separate the " + std::to_string(p) +
                       " parameters of " + form->name() + " (e.g. a single distance or angle)";
      return result;
    }
  }
  ceres::Problem problem;
  try {
    BuildProblem(*form, samples, params, result.values.data(), &problem);
  } catch (const std::invalid_argument& e) {
    result.message = e.what();
    return result;
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = params.max_iterations;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-12;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  result.solver_report = summary.BriefReport();
  result.iterations = static_cast<int>(summary.iterations.size());
  result.final_cost = summary.final_cost;
  if (!summary.IsSolutionUsable()) {
    result.message = "the solver failed: " + summary.message;
    return result;
  }
  double sum2 = 0.0, sum_abs = 0.0, wsum2 = 0.0;
  for (const auto& s : samples) {
    const double r = form->Bias(result.values.data(), s.x) - s.target_m;
    result.residuals_m.push_back(r);
    sum2 += r * r;
    sum_abs += std::abs(r);
    wsum2 += s.weight * r * r;
  }
  const double n = static_cast<double>(samples.size());
  result.rmse_m = std::sqrt(sum2 / n);
  result.mae_m = sum_abs / n;
  result.residual_std_m =
      samples.size() > static_cast<size_t>(p) ? std::sqrt(wsum2 / (n - p)) : NAN;
  if (params.compute_covariance && std::isfinite(result.residual_std_m)) {
    ceres::Covariance::Options copt;
    copt.algorithm_type = ceres::DENSE_SVD;
    copt.num_threads = 1;
    ceres::Covariance covariance(copt);
    std::vector<std::pair<const double*, const double*>> blocks = {
        {result.values.data(), result.values.data()}};
    if (covariance.Compute(blocks, &problem)) {
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> c(p, p);
      covariance.GetCovarianceBlock(result.values.data(), result.values.data(), c.data());
      // Ceres assumes unit-variance residuals; the data residuals have variance σ².
      result.covariance = c * (result.residual_std_m * result.residual_std_m);
      result.covariance_ok = true;
    }
  }
  result.success = true;
  return result;
}

double GuardedBias(double bias_m, const Features& x, const NearGuard& guard, double* share) {
  if (!guard.enabled()) {
    if (share) *share = 1.0;
    return bias_m;
  }
  const double z = x.depth_m;
  const double raw_m = z / std::cos(x.angle_rad);  // the range the camera measured
  return z - guard.Apply(z - bias_m, raw_m, share);
}

double PredictBias(const FitResult& fit, const Features& x) {
  return GuardedBias(fit.form->Bias(fit.values.data(), x), x, fit.guard);
}

double PredictiveStd(const FitResult& fit, const Features& x) {
  double share = 1.0;
  GuardedBias(fit.form->Bias(fit.values.data(), x), x, fit.guard, &share);
  double s2 = 0.0;
  if (fit.residual_model.known) {
    s2 = fit.residual_model.VarianceM2(x.depth_m);
  } else if (std::isfinite(fit.residual_std_m)) {
    s2 = fit.residual_std_m * fit.residual_std_m;
  }
  if (!fit.covariance_ok) return std::sqrt(s2);
  const auto g = fit.form->BiasGradient(fit.values.data(), x);
  const Eigen::Map<const Eigen::VectorXd> gv(g.data(), static_cast<Eigen::Index>(g.size()));
  return std::sqrt(share * share * gv.dot(fit.covariance * gv) + s2);
}

}  // namespace depthbias::model
