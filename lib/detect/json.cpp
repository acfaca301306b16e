#include "detect/json.h"

#include <cmath>
#include <cstdio>

namespace depthbias::detect {
namespace {

// A number JSON can hold: fixed decimals, null for NaN or infinity.
void Number(std::string* out, double v, int decimals) {
  if (!std::isfinite(v)) {
    *out += "null";
    return;
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  *out += buf;
}

}  // namespace

std::string FormatJsonLine(const FrameDetections& d) {
  std::string s = "{\"frame\": " + std::to_string(d.frame) + ", \"timestamp_s\": ";
  Number(&s, d.timestamp_s, 6);
  s += ", \"obstacles\": [";
  for (size_t i = 0; i < d.obstacles.size(); ++i) {
    const DetectedObstacle& o = d.obstacles[i];
    s += i ? ", {" : "{";
    s += "\"centroid_m\": [";
    for (int k = 0; k < 3; ++k) {
      if (k) s += ", ";
      Number(&s, o.centroid_m[k], 3);
    }
    s += "], \"azimuth_deg\": ";
    Number(&s, o.azimuth_deg, 2);
    s += ", \"range_m\": ";
    Number(&s, o.range_m, 3);
    s += ", \"corrected_range_m\": ";
    Number(&s, o.corrected_range_m, 3);
    s += ", \"std_m\": ";
    Number(&s, o.std_m, 3);
    s += ", \"safe_range_m\": ";
    Number(&s, o.safe_range_m, 3);
    s += ", \"zone\": \"" + ZoneName(o.zone) + "\", \"points\": " + std::to_string(o.points) + "}";
  }
  s += "]}\n";
  return s;
}

}  // namespace depthbias::detect
