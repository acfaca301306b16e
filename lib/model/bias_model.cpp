#include "model/bias_model.h"

#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "model/domain.h"
#include "model/fit.h"
#include "records/number_text.h"

namespace depthbias::model {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

// The model is even in α: a reading at −20° is corrected as one at 20°.
Features At(double depth_m, double angle_deg) {
  return {depth_m, std::abs(angle_deg) * kDegToRad};
}

// A parameter that is a depth scale (true depth over nominal: k of disp_scale, k0 of disp_tan,
// every knot of disp_knots): zero or negative has no physical meaning.
bool IsScale(const ParamSpec& p) {
  return p.unit == "1" && p.prior_mean == 1.0;
}

bool Matches(const std::string& key, const std::string& value) {
  return key == "*" || value == "*" || key == value;
}

}  // namespace

ScenarioModel::ScenarioModel(const records::BiasWeightsGroup& group,
                             const FormConstants& constants, const std::string& model,
                             const NearGuard& guard)
    : group_(group), guard_(guard) {
  residual_.known = group.margin.known;
  residual_.placement_m = group.margin.placement_m;
  residual_.noise_per_m = group.margin.noise_per_m;
  FormConstants c = constants;
  c.knots_deg = group.knots_deg;
  form_ = MakeForm(model, c);
  const std::string label = group.light + "/" + group.preset;
  const auto& params = form_->params();
  if (group.names.size() != params.size() || group.values.size() != params.size()) {
    throw std::invalid_argument("group " + label + ": " + std::to_string(group.values.size()) +
                                " weights, model " + model + " has " +
                                std::to_string(params.size()));
  }
  for (size_t j = 0; j < params.size(); ++j) {
    if (group.names[j] != params[j].name) {
      throw std::invalid_argument("group " + label + ": weight '" + group.names[j] +
                                  "' where model " + model + " has '" + params[j].name + "'");
    }
    if (!std::isfinite(group.values[j])) {
      throw std::invalid_argument("group " + label + ": weight '" + group.names[j] +
                                  "' is not finite");
    }
  }
  // Input ranges: a negative or infinite scatter, or a covariance that is not one (a negative
  // variance, asymmetric, not positive semi-definite), would make the margin less conservative
  // than the fit says. A NaN scatter means unknown (n <= p): PredictiveStdM is then NaN.
  if (group.residual_std_m < 0 || std::isinf(group.residual_std_m)) {
    throw std::invalid_argument("group " + label + ": residual_std_m " +
                                records::NumberText(group.residual_std_m) +
                                " is not a standard deviation");
  }
  if (!group.covariance.empty()) {
    const auto p = static_cast<Eigen::Index>(params.size());
    if (static_cast<Eigen::Index>(group.covariance.size()) != p) {
      throw std::invalid_argument("group " + label + ": covariance is not " +
                                  std::to_string(p) + "x" + std::to_string(p));
    }
    covariance_.resize(p, p);
    for (Eigen::Index i = 0; i < p; ++i) {
      const auto& row = group.covariance[static_cast<size_t>(i)];
      if (static_cast<Eigen::Index>(row.size()) != p) {
        throw std::invalid_argument("group " + label + ": covariance is not " +
                                    std::to_string(p) + "x" + std::to_string(p));
      }
      for (Eigen::Index j = 0; j < p; ++j) covariance_(i, j) = row[static_cast<size_t>(j)];
    }
    if (!covariance_.allFinite()) {
      throw std::invalid_argument("group " + label + ": covariance has a non-finite entry");
    }
    const double scale = covariance_.diagonal().cwiseAbs().maxCoeff();
    if ((covariance_ - covariance_.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) {
      throw std::invalid_argument("group " + label + ": covariance is not symmetric");
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(covariance_,
                                                             Eigen::EigenvaluesOnly);
    if (covariance_.diagonal().minCoeff() < 0 ||
        (p > 0 && eig.eigenvalues().minCoeff() < -1e-9 * scale)) {
      throw std::invalid_argument("group " + label +
                                  ": covariance is not positive semi-definite (a negative "
                                  "variance would shrink the margin)");
    }
  }
  CheckPhysical(label);
}

void ScenarioModel::CheckPhysical(const std::string& label) const {
  const auto& params = form_->params();
  for (size_t j = 0; j < params.size(); ++j) {
    if (IsScale(params[j]) && !(group_.values[j] > 0.0)) {
      throw std::invalid_argument("group " + label + ": weight '" + params[j].name + "' is " +
                                  records::NumberText(group_.values[j]) +
                                  ": a depth scale must be > 0");
    }
  }
  for (double knot : group_.knots_deg) {
    if (!(std::abs(knot) < kMaxAngleDeg)) {
      throw std::invalid_argument("group " + label + ": knot " + records::NumberText(knot) +
                                  " deg is at or beyond " + records::NumberText(kMaxAngleDeg) +
                                  " deg off axis");
    }
  }
  if (residual_.known) {
    const double far2 = residual_.VarianceM2(kCheckMaxDepthM);
    if (!std::isfinite(residual_.placement_m) || !std::isfinite(residual_.noise_per_m) ||
        residual_.placement_m < 0 || residual_.noise_per_m < 0 || !std::isfinite(far2)) {
      throw std::invalid_argument(
          "group " + label + ": margin placement_m " +
          records::NumberText(residual_.placement_m) + ", noise_per_m " +
          records::NumberText(residual_.noise_per_m) + ": sigma at " +
          records::NumberText(kCheckMaxDepthM) + " m is not a finite distance");
    }
  }
  // Over the readings a D455 gives, the correction and its σ must be finite numbers: a scale
  // that crosses zero off axis, a disparity offset that puts a reading beyond infinity, or σ
  // terms whose squares overflow are refused here, not written out as ±inf.
  for (double angle = 0.0; angle <= kCheckMaxAngleDeg + 1e-9; angle += 5.0) {
    const double scale = form_->Scale(group_.values.data(), angle * kDegToRad);
    if (!std::isnan(scale) && !(scale > 0.0)) {
      throw std::invalid_argument("group " + label + ": the depth scale at " +
                                  records::NumberText(angle) + " deg off axis is " +
                                  records::NumberText(scale) + ": a depth scale must be > 0");
    }
    for (double z = kMinDepthM; z <= kCheckMaxDepthM * 1.0001; z *= 1.25) {
      const double b = form_->Bias(group_.values.data(), At(z, angle));
      const double s = PredictiveStdM(z, angle);
      const bool nan_std = std::isnan(s) && std::isnan(group_.residual_std_m) && !residual_.known;
      if (!std::isfinite(b) || (!std::isfinite(s) && !nan_std)) {
        throw std::invalid_argument(
            "group " + label + ": at depth " + records::NumberText(z) + " m and " +
            records::NumberText(angle) + " deg the weights give a bias of " +
            records::NumberText(b) + " m and a sigma of " + records::NumberText(s) +
            " m: not finite numbers");
      }
    }
  }
}

double ScenarioModel::FittedBiasM(double depth_m, double angle_deg) const {
  // Outside the model's domain (domain.h) there is no prediction.
  if (!OutsideDomain(depth_m, angle_deg).empty()) return NAN;
  return form_->Bias(group_.values.data(), At(depth_m, angle_deg));
}

double ScenarioModel::BiasM(double depth_m, double angle_deg) const {
  return GuardedBias(FittedBiasM(depth_m, angle_deg), At(depth_m, angle_deg), guard_);
}

double ScenarioModel::CorrectedM(double depth_m, double angle_deg) const {
  return depth_m - BiasM(depth_m, angle_deg);
}

double ScenarioModel::RawRangeM(double depth_m, double angle_deg) {
  return depth_m / std::cos(angle_deg * kDegToRad);
}

bool ScenarioModel::NearGuarded(double depth_m, double angle_deg) const {
  double share = 1.0;
  GuardedBias(FittedBiasM(depth_m, angle_deg), At(depth_m, angle_deg), guard_, &share);
  return share < 1.0;
}

double ScenarioModel::PredictiveStdM(double depth_m, double angle_deg) const {
  if (!OutsideDomain(depth_m, angle_deg).empty()) return NAN;
  double share = 1.0;
  GuardedBias(FittedBiasM(depth_m, angle_deg), At(depth_m, angle_deg), guard_, &share);
  double s2 = 0.0;
  if (residual_.known) {
    s2 = residual_.VarianceM2(depth_m);
  } else {
    s2 = group_.residual_std_m * group_.residual_std_m;  // NaN (unknown): no margin is claimed
  }
  if (covariance_.size() == 0) return std::sqrt(s2);
  const auto g = form_->BiasGradient(group_.values.data(), At(depth_m, angle_deg));
  const Eigen::Map<const Eigen::VectorXd> gv(g.data(), static_cast<Eigen::Index>(g.size()));
  return std::sqrt(share * share * std::max(0.0, gv.dot(covariance_ * gv)) + s2);
}

double ScenarioModel::SafeDistanceM(double depth_m, double angle_deg, double k) const {
  return CorrectedM(depth_m, angle_deg) - k * PredictiveStdM(depth_m, angle_deg);
}

bool ScenarioModel::CorrectPoint(Eigen::Vector3d* p) const {
  const double z = p->z();
  const double range = p->norm();
  if (!(z > 0.0) || !std::isfinite(range)) return false;
  const double angle_deg = std::atan2(std::hypot(p->x(), p->y()), z) / kDegToRad;
  const double corrected = CorrectedM(z, angle_deg);
  if (!std::isfinite(corrected) || !(corrected > 0.0)) return false;
  *p *= corrected / range;
  return true;
}

int ScenarioModel::CorrectCloud(std::vector<Eigen::Vector3d>* points) const {
  int failed = 0;
  for (auto& p : *points) failed += CorrectPoint(&p) ? 0 : 1;
  return failed;
}

BiasModel::BiasModel(const records::BiasWeights& weights) : weights_(weights) {
  if (weights.groups.empty()) throw std::invalid_argument("the weights hold no group");
  FormConstants c;
  c.focal_px = weights.focal_px;
  c.baseline_m = weights.baseline_m;
  NearGuard guard{weights.near_m, weights.full_m};
  std::string why;
  if (!guard.IsValid(&why)) throw std::invalid_argument(why);
  for (const auto& g : weights.groups) scenarios_.emplace_back(g, c, weights.model, guard);
}

const ScenarioModel* BiasModel::Find(const std::string& light, const std::string& preset,
                                     const std::string& emitter) const {
  for (const auto& s : scenarios_) {
    const auto& g = s.group();
    if (Matches(g.light, light) && Matches(g.preset, preset) && Matches(g.emitter, emitter)) {
      return &s;
    }
  }
  return nullptr;
}

bool BiasModel::Has(const std::string& light, const std::string& preset,
                    const std::string& emitter) const {
  return Find(light, preset, emitter) != nullptr;
}

const ScenarioModel& BiasModel::Scenario(const std::string& light, const std::string& preset,
                                         const std::string& emitter) const {
  if (const ScenarioModel* s = Find(light, preset, emitter)) return *s;
  std::string held;
  for (const auto& s : scenarios_) {
    held += (held.empty() ? "" : ", ") + s.group().light + "/" + s.group().preset;
    if (s.group().emitter != "*") held += "/" + s.group().emitter;
  }
  throw std::out_of_range("no model for scenario light '" + light + "', preset '" + preset +
                          "' (the weights hold: " + held + ")");
}

}  // namespace depthbias::model
