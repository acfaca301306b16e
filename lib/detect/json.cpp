#include "detect/json.h"

#include "records/json_writer.h"

namespace depthbias::detect {

std::string FormatJsonLine(const FrameDetections& d, bool safe_beyond_raw) {
  records::JsonWriter w(records::JsonWriter::Layout::kOneLine);
  w.BeginObject()
      .Integer("frame", static_cast<long long>(d.frame))
      .Number("timestamp_s", d.timestamp_s, 15)
      .String("status", d.blind ? "blind" : "ok")
      .Number("valid_pct", d.valid_pct)
      .String("zone", ZoneName(d.zone))
      .Number("disparity_noise_px", d.disparity_noise_px)
      .String("disparity_noise_from", NoiseSourceName(d.disparity_noise_from));
  if (safe_beyond_raw) w.Bool("safe_beyond_raw", true);
  w.BeginArray("obstacles");
  for (const DetectedObstacle& o : d.obstacles) {
    w.BeginObject().BeginArray("centroid_m");
    for (int k = 0; k < 3; ++k) w.Number(o.centroid_m[k]);
    w.EndArray()
        .Number("azimuth_deg", o.azimuth_deg)
        .Number("range_m", o.range_m)
        .Number("corrected_range_m", o.corrected_range_m)
        .Number("std_m", o.std_m)
        .Number("safe_range_m", o.safe_range_m)
        .String("zone", ZoneName(o.zone))
        .Integer("points", o.points)
        .EndObject();
  }
  w.EndArray().EndObject();
  return w.Text();
}

}  // namespace depthbias::detect
