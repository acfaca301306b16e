#pragma once
// Parameters of panel extraction: detection (accumulation, RANSAC ground and panel planes,
// clustering, scoring), the panel's image region and the metrics. Defaults are the D455 at
// 1280×720 outdoors with the article's 1×1 m panel; YAML overrides only the keys it names.

#include <cstdint>
#include <string>
#include <vector>

#include "camera/intrinsics.h"

namespace depthbias::panel {

struct PanelParams {
  // Target.
  double panel_width_m = 1.0;   // nominal panel size
  double panel_height_m = 1.0;
  double size_tolerance = 0.4;  // accepted relative size error of a candidate (0.4 = ±40 %)

  // Sensor (for noise-aware thresholds and disparity-unit metrics).
  double baseline_m = camera::D455::kBaselineM;  // stereo baseline B [m]
  double expected_subpixel_rms_px = 0.08;  // disparity noise σ_d used for inlier thresholds

  // Accumulation: the first detection_frames frames of the static scene are pooled for
  // detection (0: every frame); then the recording is read again from the start to measure.
  int detection_frames = 30;
  // Keep the pooled frames to measure them (memory: detection_frames frames, 1.8 MB each at
  // 1280×720) instead of reading the recording a second time from the start.
  bool keep_detection_frames = true;

  // Detection cloud: the accumulated depth image binned into blocks of block_px × block_px;
  // 0 picks width / 320 (4 at 1280×720).
  int block_px = 0;
  double max_depth_m = 40.0;  // farther points are ignored
  double min_depth_m = 0.3;

  // Ground: RANSAC plane roughly perpendicular to the camera's up axis (−y).
  bool remove_ground = true;
  double ground_distance_m = 0.08;   // inlier distance to the ground plane
  double ground_max_angle_deg = 25;  // allowed angle between ground normal and camera −y
  double min_ground_fraction = 0.05; // of the cloud, below this no ground is assumed

  // Clustering of the non-ground points in (x/z, y/z, k·ln z) space: neighbours within
  // cluster_angle_rad in direction and cluster_relative_depth in depth join.
  double cluster_angle_rad = 0.02;
  double cluster_relative_depth = 0.06;
  int min_cluster_points = 12;
  int max_clusters = 30;
  int max_planes_per_cluster = 3;

  // Panel plane RANSAC and refinement: inlier if the depth residual is within
  // plane_sigma_k·σ_Z(Z) + plane_distance_m, σ_Z = Z²·σ_d/(f·B).
  double plane_sigma_k = 3.0;
  double plane_distance_m = 0.02;
  int ransac_max_iterations = 500;
  double ransac_probability = 0.999;
  double max_facing_angle_deg = 75.0;  // panel normal vs direction to the camera
  int refine_iterations = 3;

  // The panel's known size fitted on a candidate plane (panel/panel_fit.h): observed pixels are
  // on the plane, behind it, in front of it or on the ground when their mean depth departs from
  // the plane by more than evidence_sigma_k·σ_Z/√n + plane_distance_m. The window maximises
  // on − see_through_weight·(behind + ground) − front_weight·in front over a search area of
  // search_extent panel sizes on each side of the candidate.
  double evidence_sigma_k = 4.0;
  double see_through_weight = 2.0;
  double front_weight = 0.5;
  // per on-plane pixel in the one-pixel band just outside the window's sides and top
  double edge_weight = 20.0;
  double search_extent = 0.75;
  // How the holes enclosed by observations take the nearest observation's class
  // (panel/hole_fill.h): "opencv" (cv::distanceTransform, DIST_LABEL_PIXEL) or "sweeps" (four
  // directional sweeps, kept for comparison: lib/panel/README.md).
  std::string hole_fill = "opencv";
  // A panel is solid and stands free: a candidate is refused when more than max_see_through of
  // its window's observed pixels show the background or the ground, when the plane continues on
  // three or four sides of a ring ring_width_frac·size wide around the window (a wall, a hedge;
  // a person holding the panel or its stand take one or two sides), or when the plane's pixels cover less than min_coverage of its width or
  // height (a smaller object).
  double max_see_through = 0.25;
  double ring_width_frac = 0.15;
  double min_coverage = 0.6;

  // Optional search window from the manifest's nominal distance and angle (when known).
  bool use_search_window = true;
  double window_distance_frac = 0.3;  // |range − nominal| ≤ frac·nominal + window_distance_m
  double window_distance_m = 1.0;
  double window_angle_deg = 12.0;     // |off-axis angle − nominal| ≤ this

  // Region: the panel outline shrunk by region_margin_px pixels' footprint on every side so
  // that pixels straddling the edge are left out.
  double region_margin_px = 0.5;

  std::uint64_t seed = 1;  // RANSAC sampling

  bool IsValid(std::string* why) const;

  // Sets one named parameter from text (as a YAML scalar gives it). Returns false with a reason
  // for an unknown key or a value that does not parse.
  bool Set(const std::string& key, const std::string& value, std::string* why);
  static std::vector<std::string> Keys();
};

}  // namespace depthbias::panel
