#pragma once
// Honest margins: what a corrected distance is worth, depending on where the reading is.
//
//  - ResidualModel: the scatter a bias model does not explain, as a function of the measured
//    depth Z. Stereo physics gives two terms: a placement term that does not depend on range
//    (where the target really stood, the ground truth's own error, the panel's extent) and a
//    disparity term: a disparity error of σ_d px moves the depth by σ_Z = Z²·σ_d/(f·B), so
//        σ²(Z) = σ_place² + (c·Z²)²,   c = σ_d/(f·B)  [1/m]        (DESIGN.md "Safety margins")
//    Both are fitted (FitResidualModel), not assumed.
//  - NearGuard: never move a near reading farther on the strength of far rows. Below a measured
//    range of near_m a correction that would put the target farther than the camera measured it
//    is not applied; between near_m and full_m it is blended in linearly; corrections that bring
//    a reading nearer always apply.

#include <string>
#include <vector>

namespace depthbias::model {

struct ResidualModel {
  double placement_m = 0.0;   // σ_place [m]
  double noise_per_m = 0.0;   // c [1/m]: σ_d/(f·B) of the disparity scatter between recordings
  bool known = false;         // false: no fitted model (weights of an older schema)

  // σ²(Z) = σ_place² + (c·Z²)² [m²].
  double VarianceM2(double depth_m) const {
    const double noise_m = noise_per_m * depth_m * depth_m;
    return placement_m * placement_m + noise_m * noise_m;
  }
};

struct NearGuard {
  double near_m = 0.0;  // below this measured range a farther-moving correction is not applied
  double full_m = 0.0;  // from this measured range on it applies in full [m]; both 0: off

  bool enabled() const { return full_m > 0.0; }
  bool IsValid(std::string* why) const;
  // Share in [0, 1] of a farther-moving correction applied at a measured range.
  double Share(double raw_range_m) const;
  // The distance reported for a reading whose model-corrected range is corrected_m and whose
  // measured range is raw_m (Z / cos α): corrected_m if it is nearer than raw_m, else
  // raw_m + Share(raw_m)·(corrected_m − raw_m). *share (optional) gets the factor applied.
  double Apply(double corrected_m, double raw_m, double* share = nullptr) const;
};

// One scenario's data for the residual model: measured depths and squared held-out errors.
struct ResidualData {
  std::vector<double> depth_m;
  std::vector<double> error2_m2;
};

struct ResidualFitParams {
  bool pool_noise = true;          // one c for every scenario (one camera), σ_place per scenario
  double min_placement_m = 0.01;   // floor of σ_place: the depth quantization and panel extent
  double min_noise_per_m = 1e-5;   // floor of c (a 16 m reading then still has σ ≥ 2.6 mm)
  int max_iterations = 200;

  bool IsValid(std::string* why) const;
};

struct ResidualFitResult {
  bool success = false;
  std::string message;
  std::vector<ResidualModel> models;  // one per scenario given
  std::string solver_report;          // Ceres' BriefReport()
  int iterations = 0;
  double final_cost = 0.0;            // ½ Σ (e²/σ² + ln σ²) at the optimum
};

// Maximum likelihood of the residual model: minimizes Σ_i e_i²/σ²(Z_i) + ln σ²(Z_i) over
// log σ_place (per scenario) and log c (shared if pool_noise), with Ceres. Scenarios without data
// are refused.
ResidualFitResult FitResidualModel(const std::vector<ResidualData>& scenarios,
                                   const ResidualFitParams& params);

}  // namespace depthbias::model
