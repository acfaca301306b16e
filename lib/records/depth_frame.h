#pragma once
// One depth image as the camera delivers it: 16-bit depth counts, scaled by depth units.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace depthbias::records {

struct DepthFrame {
  int width = 0;                 // [px]
  int height = 0;                // [px]
  double depth_units_m = 0.001;  // metres per count (D455 default 0.001)
  std::uint64_t frame_number = 0;
  double timestamp_ms = 0.0;     // device timestamp [ms]
  std::vector<std::uint16_t> counts;  // row-major, width·height, 0 = no depth

  std::uint16_t at(int u, int v) const { return counts[static_cast<size_t>(v) * width + u]; }
  double DepthAt(int u, int v) const { return at(u, v) * depth_units_m; }
};

}  // namespace depthbias::records
