#pragma once
// One frame's detections as one line of JSON (DESIGN.md "Detections JSONL"), written with the
// project's one JSON builder (records/json_writer.h):
//   {"frame": 0, "timestamp_s": 0.033, "status": "ok|blind", "valid_pct": 87.5,
//    "zone": "stop|slow|clear", "disparity_noise_px": σ_d,
//    "disparity_noise_from": "weights|recording|config", "obstacles": [
//    {"centroid_m": [x, y, z], "azimuth_deg": a, "range_m": r, "corrected_range_m": c,
//     "std_m": s, "safe_range_m": min(r, c − k·s), "zone": "stop|slow|clear", "points": n},
//    ...]}
// Numbers with 6 significant digits (the timestamp with 15), null where not finite; with
// `safe_beyond_raw` every line says so ("safe_beyond_raw": true). The text only: io writes it.

#include <string>

#include "detect/detector.h"

namespace depthbias::detect {

std::string FormatJsonLine(const FrameDetections& detections,
                           bool safe_beyond_raw = false);  // ends with "\n"

}  // namespace depthbias::detect
