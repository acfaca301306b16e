#pragma once
// A fitted bias model as a machine uses it: per scenario (light, preset), the bias predicted
// at any measured depth Z and off-axis angle α, the corrected distance, its predictive
// standard deviation, a safety margin, and the point-wise correction of a cloud.
// Built from the weights record (records/bias_weights.h) that io reads from the weights YAML.

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "records/bias_weights.h"
#include "model/domain.h"
#include "model/forms.h"
#include "model/margin.h"

namespace depthbias::model {

class ScenarioModel {
 public:
  // Throws std::invalid_argument when the group does not match the form (names, sizes,
  // covariance shape) or has no physical meaning (domain.h): a depth scale <= 0, a knot at or
  // beyond kMaxAngleDeg, σ terms or a correction that are not finite over the readings a D455
  // gives (depths kMinDepthM…kCheckMaxDepthM, angles 0…kCheckMaxAngleDeg).
  ScenarioModel(const records::BiasWeightsGroup& group, const FormConstants& constants,
                const std::string& model, const NearGuard& guard = {});

  // Every reading takes the signed off-axis angle α [deg] and uses |α| (the model is even in α).
  // Outside the domain (OutsideDomain: Z < kMinDepthM, |α| >= kMaxAngleDeg) the answers are NaN.
  //
  // b(Z, α) = measured − nominal distance [m] as reported: the fitted bias, except where the
  // near guard holds back a correction that would move a near reading farther.
  double BiasM(double depth_m, double angle_deg) const;
  // The nominal distance (range to the target) the measurement stands for: Z − b(Z, α).
  double CorrectedM(double depth_m, double angle_deg) const;
  // The range the camera measured, Z / cos α, which the near guard falls back to [m].
  static double RawRangeM(double depth_m, double angle_deg);
  // True when the near guard holds back (part of) the model's correction at (Z, α): the model
  // leaves this reading alone, or partly.
  bool NearGuarded(double depth_m, double angle_deg) const;
  // sqrt(s²·gᵀΣg + σ²(Z)): parameter uncertainty at (Z, α) (s: the share of the correction
  // applied) plus the residual model σ²(Z) = σ_place² + (c·Z²)² [m]. Weights of schema 1 have no
  // residual model: σ² is then their constant residual std².
  double PredictiveStdM(double depth_m, double angle_deg) const;
  // Corrected distance minus k predictive standard deviations: a distance the target is not
  // nearer than, with the confidence k stands for.
  double SafeDistanceM(double depth_m, double angle_deg, double k) const;

  // A camera-frame point moved along its own ray so that its range is the corrected distance
  // for its own depth Z = p.z and off-axis angle α = atan(√(x² + y²) / z). Returns false
  // (point unchanged) when z ≤ 0 or the prediction is not finite.
  bool CorrectPoint(Eigen::Vector3d* point_m) const;
  // Every point; returns how many could not be corrected (left unchanged).
  int CorrectCloud(std::vector<Eigen::Vector3d>* points_m) const;

  const records::BiasWeightsGroup& group() const { return group_; }
  // False for weights of schema 1: σ does not depend on the range there.
  bool has_margin() const { return residual_.known; }
  const ResidualModel& residual_model() const { return residual_; }
  const NearGuard& guard() const { return guard_; }

 private:
  double FittedBiasM(double depth_m, double angle_deg) const;
  void CheckPhysical(const std::string& label) const;  // throws std::invalid_argument
  records::BiasWeightsGroup group_;
  std::shared_ptr<const Form> form_;
  Eigen::MatrixXd covariance_;  // empty if unknown
  ResidualModel residual_;
  NearGuard guard_;
};

class BiasModel {
 public:
  // Throws std::invalid_argument with a one-line reason (unknown model, parameter names that
  // do not match it, a malformed covariance, no groups).
  explicit BiasModel(const records::BiasWeights& weights);

  // The scenario for (light, preset[, emitter]); a group whose key is "*" matches any value.
  // Throws std::out_of_range naming the scenario and the ones the weights hold.
  const ScenarioModel& Scenario(const std::string& light, const std::string& preset,
                                const std::string& emitter = "*") const;
  bool Has(const std::string& light, const std::string& preset,
           const std::string& emitter = "*") const;

  const records::BiasWeights& weights() const { return weights_; }

 private:
  const ScenarioModel* Find(const std::string& light, const std::string& preset,
                            const std::string& emitter) const;
  records::BiasWeights weights_;
  std::vector<ScenarioModel> scenarios_;
};

}  // namespace depthbias::model
