#pragma once
// The D455's Visual_Preset option (rs2_rs400_visual_preset) as bags record it, and its short
// names: 0 Custom, 1 Default, 2 Hand, 3 HA (High Accuracy), 4 HD (High Density),
// 5 Medium Density, 6 Remove IR Pattern. One table for every reader and writer.

#include <string>

namespace depthbias::camera {

// Short name of a Visual_Preset value; "preset <n>" for any other value.
std::string PresetName(double visual_preset);

// Option value of a preset's short name (every name PresetName gives for 0–6); false otherwise.
bool PresetOptionValue(const std::string& preset, double* value);

}  // namespace depthbias::camera
