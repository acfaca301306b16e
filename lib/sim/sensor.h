#pragma once
// The base stereo sensor model: a rectified pinhole D455 depth camera. Per pixel and frame:
// true depth Z → disparity d = f·B/Z → + N(0, σ_d²) → quantized to the subpixel step →
// invalidated with a probability that depends on the scenario, the surface's texture (raised by
// the emitter's pattern at short range) and the nearness of a depth edge → Z = f·B/d, 0 when
// invalid or out of range.

#include <string>
#include <vector>

#include "camera/intrinsics.h"

namespace depthbias::sim {

// Noise and invalidation of one scenario (preset × light).
struct ScenarioParams {
  std::string light;            // "daylight", "sunset", ...
  std::string preset;           // "HA", "HD", ...
  double sigma_d_px = 0.08;     // disparity noise standard deviation [px]
  double invalid_prob = 0.2;    // hole probability of a panel-textured pixel, emitter off
};

struct SensorParams {
  camera::Intrinsics intrinsics = camera::D455::DepthIntrinsics();  // rectified: no distortion
  double baseline_m = camera::D455::kBaselineM;
  double depth_units_m = 0.001;          // [m per count]
  double subpixel_step_px = camera::D455::kSubpixelStepPx;  // disparity quantization [px]
  double min_depth_m = 0.4;              // nearer → 0 [m]
  double max_depth_m = 25.0;             // farther → 0 [m]
  // Invalidation: logit(p) = logit(p_scenario) − texture_slope·(t − reference_texture), t the
  // surface's texture plus the emitter's: emitter_texture·min(1, (emitter_reach_m / Z)²).
  double texture_slope = 6.0;
  double reference_texture = 0.2;        // the texture p_scenario is stated for (grey panel)
  double emitter_texture = 0.05;         // texture the projector adds at or below its reach
  double emitter_reach_m = 4.0;          // [m]
  // Depth edges: neighbours whose depths differ by more than edge_jump_rel (relative) are an
  // edge; pixels on its far side (the occluded background, seen by one camera only) within
  // edge_band_px of it have at least edge_invalid_prob of being holes.
  double edge_jump_rel = 0.05;
  int edge_band_px = 3;
  double edge_invalid_prob = 0.5;
  ScenarioParams fallback;               // for a scenario the table does not list
  std::vector<ScenarioParams> scenarios;

  bool IsValid(std::string* why) const;
  double focal_px() const { return intrinsics.fx; }
  // The table's entry for (light, preset), or the fallback (found = false).
  ScenarioParams Scenario(const std::string& light, const std::string& preset,
                          bool* found = nullptr) const;
};

}  // namespace depthbias::sim
