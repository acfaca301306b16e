#include "detect/noise.h"

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

}  // namespace depthbias::detect
