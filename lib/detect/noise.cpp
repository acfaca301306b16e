#include "detect/noise.h"

#include <cmath>
#include <limits>

namespace depthbias::detect {

bool NoiseParams::IsValid(std::string* why) const {
  if (frames < 2 || frames > 100000) {
    if (why) *why = "noise.frames must be in [2, 100000] (pairs of consecutive frames)";
    return false;
  }
  if (min_pairs < 1) {
    if (why) *why = "noise.min_pairs must be >= 1";
    return false;
  }
  return true;
}

std::string NoiseSourceName(NoiseSource source) {
  switch (source) {
    case NoiseSource::kConfig: return "config";
    case NoiseSource::kRecording: return "recording";
    case NoiseSource::kWeights: return "weights";
  }
  return "config";
}

double WeightsDisparityNoisePx(const records::BiasWeightsGroup& group,
                               const std::string& preset) {
  const records::BiasDisparityNoise& n = group.disparity_noise;
  if (!n.known || group.preset != preset || !(n.sigma_px > 0) || !std::isfinite(n.sigma_px))
    return std::numeric_limits<double>::quiet_NaN();
  return n.sigma_px;
}

}  // namespace depthbias::detect
