#pragma once
// The panel extraction pipeline of one recording: frames in, one row of panel metrics out, with
// the detection and region that produced it. Frames come from a FrameSource (the bag reader in
// apps/, images in memory in tests) so the library itself never touches a file.

#include <optional>
#include <string>

#include "records/depth_frame.h"
#include "records/frame_source.h"
#include "camera/intrinsics.h"
#include "records/panel_metrics.h"
#include "panel/detect.h"
#include "metrics/geometry.h"
#include "metrics/region_metrics.h"
#include "panel/params.h"

namespace depthbias::panel {

using records::FrameSource;

// The article's manual method: an image-aligned box [u0, u1) × [v0, v1) in pixels.
struct PixelBox {
  double u0 = 0, v0 = 0, u1 = 0, v1 = 0;
};

struct ExtractResult {
  records::PanelMetrics metrics;  // status "ok", "no_panel" or "error", with message
  PanelDetection detection;      // automatic mode only
  metrics::PanelRegion region;  // the panel's rectangle less the pixels shown not to be the panel
  int excluded_pixels = 0;      // rectangle pixels that showed something else than the panel
  metrics::KernelResult measure;
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
