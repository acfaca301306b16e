#include "camera/presets.h"

#include <cmath>
#include <sstream>

namespace depthbias::camera {
namespace {

constexpr const char* kNames[] = {"Custom", "Default", "Hand", "HA",
                                  "HD", "Medium Density", "Remove IR Pattern"};
constexpr int kCount = sizeof(kNames) / sizeof(kNames[0]);

}  // namespace

std::string PresetName(double visual_preset) {
  const double rounded = std::round(visual_preset);
  if (rounded == visual_preset && rounded >= 0 && rounded < kCount)
    return kNames[static_cast<int>(rounded)];
  std::ostringstream name;
  name << "preset " << visual_preset;
  return name.str();
}

bool PresetOptionValue(const std::string& preset, double* value) {
  for (int k = 0; k < kCount; ++k) {
    if (preset == kNames[k]) {
      *value = k;
      return true;
    }
  }
  return false;
}

}  // namespace depthbias::camera
