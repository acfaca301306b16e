#pragma once
// The disparity noise σ_d of a recording, from its own frames: the temporal spread at its
// obstacles (camera/disparity_noise.h: σ_d = σ(Δd)/√2 of consecutive frames, robust RMS). A
// camera that moves between frames widens Δd: σ_d then comes out larger, which makes the margin
// wider, not narrower.

#include <string>

#include "camera/disparity_noise.h"

namespace depthbias::detect {

struct NoiseParams {
  bool from_frames = true;  // false: σ_d of the margin is cluster.disparity_noise_px
  int frames = 30;          // the first frames of a recording the estimate is taken from
  int min_pairs = 200;      // fewer pixel pairs at obstacles: the estimate is not used [pairs]
  bool IsValid(std::string* why) const;
};

// The estimator itself is camera's (one definition, shared with the metrics kernel's panel
// measurement, the metrics CSV's sigma_d_px).
using camera::TemporalNoise;

}  // namespace depthbias::detect
