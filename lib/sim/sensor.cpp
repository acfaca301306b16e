#include "sim/sensor.h"

#include <cmath>
#include <cstdio>

namespace depthbias::sim {
namespace {

bool Fail(std::string* why, const std::string& message) {
  if (why) *why = message;
  return false;
}

bool ScenarioValid(const ScenarioParams& s, std::string* why) {
  const std::string id = s.light.empty() ? "fallback" : s.light + "/" + s.preset;
  if (!(s.sigma_d_px >= 0) || !std::isfinite(s.sigma_d_px))
    return Fail(why, "scenario " + id + ": sigma_d_px must be >= 0");
  if (!(s.invalid_prob >= 0 && s.invalid_prob <= 1))
    return Fail(why, "scenario " + id + ": invalid_prob must be in [0, 1]");
  return true;
}

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

bool SensorParams::IsValid(std::string* why) const {
  if (!intrinsics.IsValid(why)) return false;
  if (!camera::IsDistortionZero(intrinsics))
    return Fail(why, "the sensor is a rectified pinhole: distortion coefficients must be 0");
  if (!(baseline_m > 0)) return Fail(why, "baseline_m must be > 0");
  if (!(depth_units_m > 0)) return Fail(why, "depth_units_m must be > 0");
  if (!(subpixel_step_px > 0)) return Fail(why, "subpixel_step_px must be > 0");
  if (!(min_depth_m > 0) || !(max_depth_m > min_depth_m))
    return Fail(why, "need 0 < min_depth_m < max_depth_m");
  if (max_depth_m / depth_units_m > 65535)
    return Fail(why, "max_depth_m " + Number(max_depth_m) +
                         " does not fit 16-bit counts at depth units of " +
                         Number(depth_units_m) + " m (at most " +
                         Number(65535 * depth_units_m) + " m)");
  if (focal_px() * baseline_m / min_depth_m / subpixel_step_px > 1e6)
    return Fail(why, "min_depth_m too small for the subpixel step (disparity table too big)");
  if (!(texture_slope >= 0)) return Fail(why, "texture_slope must be >= 0");
  if (!(emitter_texture >= 0) || !(emitter_reach_m > 0))
    return Fail(why, "emitter_texture must be >= 0 and emitter_reach_m > 0");
  if (!(edge_jump_rel > 0)) return Fail(why, "edge_jump_rel must be > 0");
  if (edge_band_px < 0 || edge_band_px > 50) return Fail(why, "edge_band_px must be in [0, 50]");
  if (!(edge_invalid_prob >= 0 && edge_invalid_prob <= 1))
    return Fail(why, "edge_invalid_prob must be in [0, 1]");
  if (!ScenarioValid(fallback, why)) return false;
  for (const auto& s : scenarios)
    if (!ScenarioValid(s, why)) return false;
  return true;
}

ScenarioParams SensorParams::Scenario(const std::string& light, const std::string& preset,
                                      bool* found) const {
  for (const auto& s : scenarios) {
    if (s.light == light && s.preset == preset) {
      if (found) *found = true;
      return s;
    }
  }
  if (found) *found = false;
  ScenarioParams s = fallback;
  s.light = light;
  s.preset = preset;
  return s;
}

}  // namespace depthbias::sim
