#include "detect/params.h"

#include <cmath>

namespace depthbias::detect {
namespace {

bool Fail(std::string* why, const std::string& message) {
  if (why) *why = message;
  return false;
}

bool Positive(double v) { return v > 0.0 && std::isfinite(v); }

}  // namespace

bool CloudParams::IsValid(std::string* why) const {
  if (stride_px < 1 || stride_px > 64) return Fail(why, "cloud.stride_px must be in [1, 64]");
  if (!(min_range_m >= 0.0) || !(max_range_m > min_range_m) || !std::isfinite(max_range_m))
    return Fail(why, "cloud: need 0 <= min_range_m < max_range_m");
  if (!(min_valid_pct >= 0.0 && min_valid_pct <= 100.0))
    return Fail(why, "cloud.min_valid_pct must be in [0, 100]");
  return true;
}

bool VoxelParams::IsValid(std::string* why) const {
  if (!(leaf_m >= 0.01 && leaf_m <= 2.0)) return Fail(why, "voxel.leaf_m must be in [0.01, 2]");
  return true;
}

bool GroundParams::IsValid(std::string* why) const {
  if (!(max_tilt_deg > 0.0 && max_tilt_deg < 90.0))
    return Fail(why, "ground.max_tilt_deg must be in (0, 90)");
  if (!Positive(distance_m)) return Fail(why, "ground.distance_m must be > 0");
  if (max_iterations < 1) return Fail(why, "ground.max_iterations must be >= 1");
  if (!(probability > 0.0 && probability < 1.0))
    return Fail(why, "ground.probability must be in (0, 1)");
  if (!(min_fraction >= 0.0 && min_fraction <= 1.0))
    return Fail(why, "ground.min_fraction must be in [0, 1]");
  if (refine_iterations < 0) return Fail(why, "ground.refine_iterations must be >= 0");
  return true;
}

bool ClusterParams::IsValid(std::string* why) const {
  if (!Positive(base_tolerance_m)) return Fail(why, "cluster.base_tolerance_m must be > 0");
  if (!(noise_k >= 0.0) || !std::isfinite(noise_k))
    return Fail(why, "cluster.noise_k must be >= 0");
  if (!(disparity_noise_px >= 0.0) || !std::isfinite(disparity_noise_px))
    return Fail(why, "cluster.disparity_noise_px must be >= 0");
  if (min_points < 1) return Fail(why, "cluster.min_points must be >= 1");
  return true;
}

bool ObstacleParams::IsValid(std::string* why) const {
  if (!(min_height_m >= 0.0) || !std::isfinite(min_height_m))
    return Fail(why, "obstacle.min_height_m must be >= 0");
  if (min_points < 1) return Fail(why, "obstacle.min_points must be >= 1");
  return true;
}

bool ZoneParams::IsValid(std::string* why) const {
  if (!(speed_mps >= 0.0) || !std::isfinite(speed_mps))
    return Fail(why, "zones.speed_mps must be >= 0");
  if (!(reaction_s >= 0.0) || !std::isfinite(reaction_s))
    return Fail(why, "zones.reaction_s must be >= 0");
  if (!Positive(decel_mps2)) return Fail(why, "zones.decel_mps2 must be > 0");
  if (!(clearance_m >= 0.0) || !std::isfinite(clearance_m))
    return Fail(why, "zones.clearance_m must be >= 0");
  if (!(slow_margin_m >= 0.0) || !std::isfinite(slow_margin_m))
    return Fail(why, "zones.slow_margin_m must be >= 0");
  return true;
}

double ZoneParams::StoppingDistanceM() const {
  // S = v·T + v²/(2a) + C: travel during the reaction, braking distance, clearance.
  return speed_mps * reaction_s + speed_mps * speed_mps / (2.0 * decel_mps2) + clearance_m;
}

bool DetectorParams::IsValid(std::string* why) const {
  if (!cloud.IsValid(why) || !voxel.IsValid(why) || !ground.IsValid(why) ||
      !cluster.IsValid(why) || !obstacle.IsValid(why) || !zones.IsValid(why) ||
      !noise.IsValid(why))
    return false;
  // k standard deviations: 2 leaves about 2.5 % of truths nearer than the safe range; 0 claims
  // no margin at all, and beyond 10 the safe range says nothing any more.
  if (!(k > 0.0 && k <= kMaxK)) return Fail(why, "k must be in (0, 10]");
  if (!Positive(baseline_m)) return Fail(why, "baseline_m must be > 0");
  return true;
}

}  // namespace depthbias::detect
