#pragma once
// Panel detection on a static scene: frames are pooled into a per-pixel mean depth image
// (DepthAccumulator), deprojected into a cloud, the ground removed by RANSAC, the rest clustered,
// planes found in each cluster by RANSAC and scored as the panel (size, shape, planarity, facing
// the camera, optional search window), and the winner refined on all its inlier pixels.

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "records/depth_frame.h"
#include "metrics/geometry.h"
#include "panel/params.h"

namespace depthbias::panel {

// Per-pixel count of valid samples and sum of depth counts over the frames added.
class DepthAccumulator {
 public:
  DepthAccumulator(int width, int height);
  void Add(const records::DepthFrame& frame);
  int width() const { return width_; }
  int height() const { return height_; }
  std::uint64_t frames() const { return frames_; }
  std::uint32_t Count(std::size_t i) const { return n_[i]; }
  double depth_units_m() const { return depth_units_m_; }
  // Sum of pixel i's depth counts over its valid samples.
  std::uint64_t SumCounts(std::size_t i) const {
    return sum_[i] + (carry_.empty() ? 0 : static_cast<std::uint64_t>(carry_[i]));
  }
  // Mean depth of pixel i over its valid samples [m]; 0 without samples.
  double MeanDepth(std::size_t i) const {
    if (n_[i] == 0) return 0.0;
    const double sum = static_cast<double>(sum_[i]) + (carry_.empty() ? 0.0 : carry_[i]);
    return sum / n_[i] * depth_units_m_;
  }

 private:
  int width_, height_;
  double depth_units_m_ = 0.001;
  std::uint64_t frames_ = 0;
  std::vector<std::uint32_t> n_;
  std::vector<std::uint32_t> sum_;  // 32-bit sums vectorize; carried over every 65535 frames
  std::vector<double> carry_;
};

// Nominal position of the panel from the manifest; NaN when unknown.
struct SearchWindow {
  double distance_m = std::nan("");
  double angle_deg = std::nan("");
  bool known() const { return std::isfinite(distance_m) || std::isfinite(angle_deg); }
};

// What the accumulated frames show in and around a panel-sized window on a candidate plane
// (panel/panel_fit.h): observed pixels by class, counted over the window, a ring around it, and
// the plane beyond it.
struct WindowEvidence {
  int on_plane = 0;       // observed pixels on the plane inside the window
  int behind = 0;         // observed pixels behind the plane inside the window
  int ground = 0;         // observed ground pixels inside the window
  int in_front = 0;       // observed pixels in front of the plane inside the window
  int ring_on_plane = 0;  // observed pixels on the plane in a ring around the window
  int ring_observed = 0;  // observed pixels (any class) in that ring
  // Sides of the ring (left, right, below, above) where most observed pixels lie on the plane:
  // a person holding the panel or a stand takes one or two, a wall or a hedge three or four.
  int occupied_sides = 0;
  int cut_off_px = 0;     // on-plane pixels of the searched area outside the window
  double cut_off_below_m = 0, cut_off_above_m = 0;  // how far they reach beyond its edges
  double cut_off_left_m = 0, cut_off_right_m = 0;
  double covered_width_m = 0, covered_height_m = 0;  // extent of the on-plane pixels inside

  // Share of the window's observed pixels that show something else than a solid panel.
  double SeeThrough() const {
    const int all = on_plane + behind + ground;
    return all > 0 ? static_cast<double>(behind + ground) / all : 1.0;
  }
  double RingShare() const {
    return ring_observed > 0 ? static_cast<double>(ring_on_plane) / ring_observed : 0.0;
  }
};

// One plane found in a cluster and how it scored.
struct PanelCandidate {
  int cluster = -1;
  int inliers = 0;       // cloud points (blocks)
  double width_m = 0, height_m = 0;  // extent of the plane's pixels inside the fitted window
  double range_m = 0, off_axis_deg = 0, facing_deg = 0;
  double see_through = 0;  // WindowEvidence::SeeThrough
  double ring_share = 0;   // WindowEvidence::RingShare
  WindowEvidence evidence;  // of its fitted window
  double cost = 0;       // lower is better
  std::string rejected;  // empty when acceptable
};

struct PanelDetection {
  bool found = false;
  std::string why_not;
  metrics::PanelRectangle panel;        // the known size, fitted and refined on the plane
  double plane_rms_m = 0.0;    // RMS orthogonal residual of the refined inliers
  int inlier_pixels = 0;       // full-resolution pixels supporting the refined plane
  WindowEvidence evidence;     // of the chosen window (cut-off parts of the plane included)
  bool ground_found = false;
  metrics::Plane ground;
  int ground_inliers = 0;
  int cloud_points = 0;        // detection cloud size (blocks with depth)
  int block_px = 0;
  int clusters = 0;
  int ransac_iterations = 0;   // summed over every RANSAC run
  std::uint64_t frames = 0;    // frames pooled
  std::vector<PanelCandidate> candidates;
  int chosen = -1;             // index into candidates
};

PanelDetection DetectPanel(const metrics::RayTable& rays, const DepthAccumulator& acc,
                           const PanelParams& params, const SearchWindow& window = {});

}  // namespace depthbias::panel
