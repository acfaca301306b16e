#pragma once
// The panel extraction pipeline of one recording: frames in, one row of panel metrics out, with
// the detection and region that produced it. Frames come from a FrameSource (the bag reader in
// apps/, images in memory in tests) so the library itself never touches a file.

#include <optional>
#include <string>

#include "camera/depth_frame.h"
#include "camera/intrinsics.h"
#include "camera/panel_metrics.h"
#include "panel/detect.h"
#include "panel/geometry.h"
#include "panel/measure.h"
#include "panel/params.h"

namespace depthbias::panel {

// A recording's depth frames, in order.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual bool Next(camera::DepthFrame* frame) = 0;  // false at the end
  // Starts again from the first frame; false when the source cannot. The automatic mode reads
  // the frames twice (detect, then measure); the box mode once.
  virtual bool Rewind() { return false; }
};

// The article's manual method: an image-aligned box [u0, u1) × [v0, v1) in pixels.
struct PixelBox {
  double u0 = 0, v0 = 0, u1 = 0, v1 = 0;
};

struct ExtractResult {
  camera::PanelMetrics metrics;  // status "ok", "no_panel" or "error", with message
  PanelDetection detection;      // automatic mode only
  PanelRegion region;
  MeasureResult measure;
  std::uint64_t frames_read = 0; // frames read, over every pass
  int passes = 0;
};

// Finds the panel (or takes the box) and measures it. metrics.bag, light, emitter, preset,
// distance_m and angle_deg are left for the caller. Exceptions thrown by the source pass
// through; bad frames and failed detections come back as a status with a message.
ExtractResult ExtractPanel(FrameSource& source, const camera::Intrinsics& intrinsics,
                           const PanelParams& params, const SearchWindow& window = {},
                           const std::optional<PixelBox>& box = std::nullopt);

// What a user needs to check a detection, as one JSON object: plane, 3D corners, image outline,
// inliers, frames, intrinsics (and any extra members given as "key": value JSON text).
std::string DetectionJson(const ExtractResult& result, const camera::Intrinsics& intrinsics,
                          const std::string& extra_members = "");

}  // namespace depthbias::panel
