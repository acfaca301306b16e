#pragma once
// The detector's stages, each a function of its own inputs, in the order
// ObstacleDetector::Detect runs them (tests/detect/stages_test.cpp tests each alone):
//   1. cloud     one depth frame's samples → camera-frame points, the valid share (blind frames)
//   2. voxels    points → one centroid per occupied cube, each point keeping its cube
//   3. ground    voxels → the ground plane (RANSAC, normal near the camera's −y) and what lies on
//                or below it
//   4. clusters  the other voxels → Euclidean clusters whose tolerance grows with range
//   5. obstacle  a cluster's own points → centroid, azimuth, off-axis angle, median depth and
//                range, height, width
//   6. margin    the bias model's corrected range, σ and the safe range
//   7. zone      the safe range → stop / slow / clear (detector.h: ZoneFor)
// PCL stays in the .cpp files.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "camera/intrinsics.h"
#include "detect/detector.h"
#include "detect/params.h"
#include "model/bias_model.h"
#include "records/depth_frame.h"

namespace depthbias::detect {

// 1. Cloud. One sample pixel per stride block (its centre), its ray at Z = 1 computed once.
struct SampleRays {
  std::vector<std::uint32_t> pixel;  // index in the frame
  std::vector<Eigen::Vector3f> ray;  // (x, y, 1) at Z = 1
  std::vector<float> ray_norm;       // |ray|: range = Z·|ray|
};
SampleRays MakeSampleRays(const camera::Intrinsics& intrinsics, int stride_px);

struct SampledCloud {
  std::vector<Eigen::Vector3f> points;  // valid samples, camera frame [m]
  std::vector<int> sample_of;           // the sample of each point
  std::vector<float> depth_m;           // Z of every sample (0: not valid)
  int samples = 0;
  double valid_pct = 0.0;               // points / samples [%] (0 without samples)
};
// Valid: a count neither 0 nor 65535 whose range lies in [min_range_m, max_range_m].
void BuildCloud(const records::DepthFrame& frame, const SampleRays& rays,
                const CloudParams& params, SampledCloud* out);
// Fewer valid samples than min_valid_pct of them, or no samples at all.
bool IsBlind(const SampledCloud& cloud, const CloudParams& params);

// 2. Voxel grid: integer cube coordinates packed in 64 bits, an open-addressing hash table from
// key to voxel, centroids accumulated in one pass. Keeps its table between frames.
class VoxelGrid {
 public:
  // voxel_of[i]: the voxel of point i; centroids: one per occupied cube, in first-seen order.
  void Build(const std::vector<Eigen::Vector3f>& points, float leaf_m, std::vector<int>* voxel_of,
             std::vector<Eigen::Vector3f>* centroids);

 private:
  std::vector<std::uint64_t> keys_;
  std::vector<int> slots_;
  std::vector<int> counts_;
};

// The same by pcl::VoxelGrid (its leaf layout kept to find each point's voxel); centroids in
// PCL's order (by cube index), not first-seen.
void PclVoxelGrid(const std::vector<Eigen::Vector3f>& points, float leaf_m,
                  std::vector<int>* voxel_of, std::vector<Eigen::Vector3f>* centroids);

// 3. Ground.
struct Ground {
  bool found = false;
  Eigen::Vector3d normal{0.0, -1.0, 0.0};  // n·p + d = 0, the camera on the + side; −y if none
  double d = 0.0;
  std::vector<char> is_ground;  // per voxel: on the ground or below it
  int inliers = 0;              // voxels removed
  int iterations = 0;           // RANSAC's
};
Ground FindGround(const std::vector<Eigen::Vector3f>& voxels, const GroundParams& params);

// 4. Clusters of the voxels that are not ground: region growing on a k-d tree, radius
// tol(r) = base_tolerance_m + noise_per_m2·r² (noise_per_m2 = noise_k·σ_d/(f·B)). Clusters of
// fewer than min_points voxels are dropped; voxel indices, in growing order.
std::vector<std::vector<int>> FindClusters(const std::vector<Eigen::Vector3f>& voxels,
                                           const std::vector<char>& is_ground,
                                           const ClusterParams& params, double noise_per_m2);

// The same by pcl::ConditionalEuclideanClustering: its radius the largest tol(r) of the cloud,
// its condition the tolerance at the point grown from.
std::vector<std::vector<int>> PclClusters(const std::vector<Eigen::Vector3f>& voxels,
                                          const std::vector<char>& is_ground,
                                          const ClusterParams& params, double noise_per_m2);

// 5. Obstacle: measured on its own points (indices into `points`); false when it stands lower
// than min_height_m above the ground (the image's vertical when there is none).
bool MeasureObstacle(const std::vector<Eigen::Vector3f>& points, const std::vector<int>& members,
                     const Ground& ground, const ObstacleParams& params, DetectedObstacle* o);

// 6. Margin: corrected range (the model's CorrectedM at the median depth and the off-axis
// angle), σ = √(model σ² + this frame's median noise²) with the median's noise
// 1.2533·Z²·σ_d/(f·B)/√n, safe range min(raw, corrected − k·σ) (corrected − k·σ alone with
// safe_beyond_raw), and the zone.
void ApplyMargin(const model::ScenarioModel& scenario, const DetectorParams& params,
                 double disparity_noise_px, double focal_baseline_px_m, DetectedObstacle* o);

}  // namespace depthbias::detect
