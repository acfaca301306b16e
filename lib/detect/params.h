#pragma once
// Parameters of the obstacle detector, one struct per stage, defaults in the structs (a D455 at
// 1280×720 on a vehicle outdoors); config/obstacle_detector.yaml overrides named keys and says
// why. Units in the names.

#include <cstdint>
#include <string>

#include "camera/intrinsics.h"
#include "detect/noise.h"

namespace depthbias::detect {

// Depth image → camera-frame points.
struct CloudParams {
  int stride_px = 4;         // one pixel per stride × stride block (the block's centre)
  double min_range_m = 0.5;  // nearer points are ignored (below the D455's minimum depth)
  double max_range_m = 20.0; // farther points are ignored (σ_Z beyond ~1 m at 20 m)
  // A frame whose valid samples (a depth, not 0 or the full-scale 65535, within
  // [min_range_m, max_range_m]) are fewer than this share of the sampled pixels is blind: the
  // camera saw too little to say the way is clear [% of the samples].
  double min_valid_pct = 5.0;
  bool IsValid(std::string* why) const;
};

// Points → one centroid per occupied cube.
struct VoxelParams {
  double leaf_m = 0.10;  // cube edge [m]
  // pcl::VoxelGrid (with its leaf layout, for each point's voxel) instead of the hash grid of
  // stages.h; the same voxels (README "PCL beside ours").
  bool use_pcl = false;
  bool IsValid(std::string* why) const;
};

// Ground: RANSAC plane whose normal is within max_tilt_deg of the camera's up axis (−y), so the
// camera's height and pitch are free; refined by least squares on its inliers; the ground and
// whatever lies below it are removed.
struct GroundParams {
  bool enabled = true;
  double max_tilt_deg = 20.0;   // ground normal vs camera −y
  double distance_m = 0.12;     // inlier band and removal height above the plane [m]
  int max_iterations = 200;
  double probability = 0.99;    // RANSAC's confidence to stop early
  double min_fraction = 0.05;   // fewer inliers (share of the voxels): no ground assumed
  int refine_iterations = 2;
  std::uint64_t seed = 1;       // RANSAC sampling
  bool IsValid(std::string* why) const;
};

// Euclidean clusters whose tolerance grows with range as the stereo noise does:
//   tol(r) = base_tolerance_m + noise_k · r²·σ_d/(f·B)         (σ_Z = Z²·σ_d/(f·B))
struct ClusterParams {
  double base_tolerance_m = 0.20;   // at short range: two voxels
  double noise_k = 1.0;             // σ_Z's that two neighbours may differ by
  // σ_d of the tolerance (D455 outdoors: 0.05–0.1 px); f and B: the camera's. It is also the
  // margin's σ_d when the recording's frames do not give one (noise.h).
  double disparity_noise_px = 0.08;
  int min_points = 6;               // voxels; smaller clusters are noise
  // pcl::ConditionalEuclideanClustering with tol(r) as its condition (its search radius the
  // largest tol of the cloud) instead of the region growing of stages.h; the same clusters.
  bool use_pcl = false;
  bool IsValid(std::string* why) const;
};

// Which clusters are obstacles.
struct ObstacleParams {
  double min_height_m = 0.30;  // extent along the ground normal (or the image's vertical)
  int min_points = 8;          // voxels
  bool IsValid(std::string* why) const;
};

// Zones from the stopping distance S = v·T + v²/(2a) + C of the machine.
struct ZoneParams {
  double speed_mps = 2.0;      // v: travel speed [m/s]
  double reaction_s = 0.5;     // T: detection-to-brake time [s]
  double decel_mps2 = 1.5;     // a: braking deceleration [m/s²]
  double clearance_m = 1.0;    // C: distance to keep at standstill [m]
  double slow_margin_m = 4.0;  // stop ≤ S < slow ≤ S + slow_margin_m < clear [m]
  bool IsValid(std::string* why) const;
  double StoppingDistanceM() const;  // S
};

constexpr double kMaxK = 10.0;  // the largest k of a safe range

struct DetectorParams {
  CloudParams cloud;
  VoxelParams voxel;
  GroundParams ground;
  ClusterParams cluster;
  ObstacleParams obstacle;
  ZoneParams zones;
  NoiseParams noise;  // σ_d of the margin: the unit's, from the recording's frames
  double k = 2.0;  // safe range = min(raw, corrected − k·σ); in (0, 10]
  // false (default): a safe range is never farther than the range the camera measured,
  // min(raw, corrected − k·σ); true: corrected − k·σ even where the model moves it farther.
  bool safe_beyond_raw = false;
  double baseline_m = camera::D455::kBaselineM;  // B of the noise model (the recording's)
  bool IsValid(std::string* why) const;
};

}  // namespace depthbias::detect
