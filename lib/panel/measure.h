#pragma once
// Streaming measurement of a panel region over a recording's frames: per-pixel running sums
// (count, ΣZ, ΣZ², Σ1/Z, Σ1/Z²) and pooled histograms of depth counts and range, so memory does
// not grow with the number of frames and the pooled median is exact.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "records/depth_frame.h"
#include "records/panel_metrics.h"
#include "panel/geometry.h"

namespace depthbias::panel {

struct MeasureResult {
  bool ok = false;
  std::string why_not;
  PlaneFit plane;              // total least squares plane of every valid region sample
  // Plane fitted in inverse depth, 1/Z = a·x/z + b·y/z + c: ordinary least squares, the maximum
  // likelihood plane for noise in disparity (along the rays). Unlike the orthogonal fit it has
  // no tilt bias when the depth noise is large against the panel size (far panels).
  bool disparity_plane_ok = false;
  Plane disparity_plane;
  std::uint64_t samples = 0;   // valid region samples pooled over frames
  std::uint64_t frames = 0;    // frames measured
  std::uint64_t frames_with_depth = 0;
};

class RegionMeasurer {
 public:
  // focal_px and baseline_m convert depth residuals to disparity (Depth Quality Tool).
  RegionMeasurer(const RayTable* rays, PanelRegion region, double baseline_m);

  // Adds one frame; the frame must match the rays' image size (checked by the caller).
  void Add(const records::DepthFrame& frame);

  // Fills the depth columns of metrics (frames, mean, median, plane std from the orthogonal fit,
  // hole rate, range, normal tilt and subpixel RMS from the disparity plane, region_px, temporal
  // std); azimuth and elevation come from center_m, the panel centre on its plane.
  MeasureResult Finish(const Eigen::Vector3d& center_m, records::PanelMetrics* metrics) const;

  const PanelRegion& region() const { return region_; }

 private:
  struct PixelSums {
    std::uint32_t n = 0;
    double z = 0, z2 = 0, inv = 0, inv2 = 0;
  };
  const RayTable* rays_;
  PanelRegion region_;
  double baseline_m_;
  double depth_units_m_ = 0.0;
  std::vector<PixelSums> sums_;
  std::vector<std::uint64_t> depth_hist_;  // by depth count
  std::vector<std::uint64_t> range_hist_;  // by range in depth units
  std::uint64_t frames_ = 0;
  std::uint64_t frames_with_depth_ = 0;
  bool mixed_units_ = false;
};

}  // namespace depthbias::panel
