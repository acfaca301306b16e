#pragma once
// The detector's parameters from YAML text (config/obstacle_detector.yaml; the app reads the
// file through io):
//   cloud: {stride_px, min_range_m, max_range_m}      voxel: {leaf_m}
//   ground: {enabled, max_tilt_deg, distance_m, max_iterations, probability, min_fraction,
//            refine_iterations, seed}
//   cluster: {base_tolerance_m, noise_k, disparity_noise_px, min_points}
//   obstacle: {min_height_m, min_points}
//   zones: {speed_mps, reaction_s, decel_mps2, clearance_m, slow_margin_m}
//   k: 2
// A document overrides only the keys it names; an unknown key, a value of the wrong type or
// parameters that are not valid give false and a one-line reason naming the key.

#include <string>

#include "detect/params.h"

namespace depthbias::detect {

bool ParseDetectorYaml(const std::string& text, DetectorParams* params, std::string* why);

}  // namespace depthbias::detect
