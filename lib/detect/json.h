#pragma once
// One frame's detections as one line of JSON (DESIGN.md "Detections JSONL"):
//   {"frame": 0, "timestamp_s": 0.033, "obstacles": [{"centroid_m": [x, y, z],
//    "azimuth_deg": a, "range_m": r, "corrected_range_m": c, "std_m": s, "safe_range_m": c − k·s,
//    "zone": "stop|slow|clear", "points": n}, ...]}
// Lengths in metres to the millimetre, angles in degrees to 0.01°. The text only: io writes it.

#include <string>

#include "detect/detector.h"

namespace depthbias::detect {

std::string FormatJsonLine(const FrameDetections& detections);  // ends with "\n"

}  // namespace depthbias::detect
