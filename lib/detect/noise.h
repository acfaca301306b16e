#pragma once
// The disparity noise σ_d of the margin's reading noise, and where it comes from: the unit's
// weights (the median of its panel recordings' sigma_d_px in the recording's scenario, written by
// fit_bias), else the recording's own frames (the temporal spread at its obstacles,
// camera/disparity_noise.h: σ_d = σ(Δd)/√2 of consecutive frames, robust RMS), else the
// configured cluster.disparity_noise_px. A camera that moves between frames widens Δd: σ_d then
// comes out larger, which makes the margin wider, not narrower.

#include <string>

#include "camera/disparity_noise.h"
#include "records/bias_weights.h"

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

// Where a margin's σ_d came from.
enum class NoiseSource { kConfig, kRecording, kWeights };
std::string NoiseSourceName(NoiseSource source);  // "config", "recording", "weights"

// σ_d of the weights for a recording of `preset` scored by `group` (the group its scenario
// picked): the group's disparity_noise when it holds one and the group is that preset's; a group
// that pools presets ("*") or another preset's gives none (σ_d is a preset's). NaN: the weights
// do not say.
double WeightsDisparityNoisePx(const records::BiasWeightsGroup& group, const std::string& preset);

}  // namespace depthbias::detect
