#include "detect/detector.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "detect/stages.h"

namespace depthbias::detect {

std::string ZoneName(Zone zone) {
  switch (zone) {
    case Zone::kStop: return "stop";
    case Zone::kSlow: return "slow";
    case Zone::kClear: return "clear";
  }
  return "clear";
}

Zone ZoneFor(double safe_range_m, const ZoneParams& zones) {
  const double s = zones.StoppingDistanceM();
  if (!(safe_range_m > s)) return Zone::kStop;  // NaN is a stop too
  if (safe_range_m <= s + zones.slow_margin_m) return Zone::kSlow;
  return Zone::kClear;
}

struct ObstacleDetector::Impl {
  camera::Intrinsics intrinsics;
  const model::ScenarioModel* scenario = nullptr;
  SampleRays rays;
  // Per-frame buffers.
  SampledCloud cloud;
  std::vector<int> voxel_of;
  std::vector<Eigen::Vector3f> voxels;
  VoxelGrid grid;
  // The depth of every sample in the frame before, for the temporal spread at the obstacles.
  std::vector<float> previous_depth;
  bool has_previous = false;
  std::uint64_t previous_index = 0;
  TemporalNoise temporal;
};

ObstacleDetector::ObstacleDetector(const camera::Intrinsics& intrinsics,
                                   const DetectorParams& params,
                                   const model::ScenarioModel& scenario)
    : params_(params), sigma_d_px_(params.cluster.disparity_noise_px),
      impl_(std::make_unique<Impl>()) {
  std::string why;
  if (!params.IsValid(&why)) throw std::invalid_argument("detector parameters: " + why);
  if (!intrinsics.IsValid(&why)) throw std::invalid_argument("intrinsics: " + why);
  if (!camera::IsDeprojectable(intrinsics))
    throw std::invalid_argument("intrinsics: this distortion model has no deprojection");
  impl_->intrinsics = intrinsics;
  impl_->scenario = &scenario;
  impl_->rays = MakeSampleRays(intrinsics, params.cloud.stride_px);
}

ObstacleDetector::~ObstacleDetector() = default;

void ObstacleDetector::SetDisparityNoisePx(double sigma_px, NoiseSource source) {
  if (!(sigma_px > 0.0) || !std::isfinite(sigma_px))
    throw std::invalid_argument("disparity noise must be > 0 px");
  sigma_d_px_ = sigma_px;
  sigma_d_from_ = source;
}

const TemporalNoise& ObstacleDetector::temporal_noise() const { return impl_->temporal; }

void ObstacleDetector::ResetTemporalNoise() {
  impl_->temporal.Clear();
  impl_->has_previous = false;
}

FrameDetections ObstacleDetector::Detect(const records::DepthFrame& frame, std::uint64_t index) {
  FrameDetections out;
  out.frame = index;
  out.timestamp_s = frame.timestamp_ms / 1000.0;
  Impl& m = *impl_;
  const DetectorParams& p = params_;
  if (frame.width != m.intrinsics.width || frame.height != m.intrinsics.height ||
      frame.counts.size() != static_cast<size_t>(frame.width) * frame.height) {
    out.message = "frame of " + std::to_string(frame.width) + "x" +
                  std::to_string(frame.height) + " where the intrinsics are " +
                  std::to_string(m.intrinsics.width) + "x" + std::to_string(m.intrinsics.height);
    return out;
  }
  out.success = true;
  out.disparity_noise_px = sigma_d_px_;
  out.disparity_noise_from = sigma_d_from_;
  const double fb = m.intrinsics.fx * p.baseline_m;  // f·B [px·m]

  // 1. Cloud, and whether the frame shows enough to say anything is clear.
  BuildCloud(frame, m.rays, p.cloud, &m.cloud);
  out.samples = m.cloud.samples;
  out.cloud_points = static_cast<int>(m.cloud.points.size());
  out.valid_pct = m.cloud.valid_pct;
  out.blind = IsBlind(m.cloud, p.cloud);
  const bool follows = m.has_previous && index == m.previous_index + 1 &&
                       m.previous_depth.size() == m.cloud.depth_m.size();

  // 2. Voxel grid.
  if (p.voxel.use_pcl) {
    PclVoxelGrid(m.cloud.points, static_cast<float>(p.voxel.leaf_m), &m.voxel_of, &m.voxels);
  } else {
    m.grid.Build(m.cloud.points, static_cast<float>(p.voxel.leaf_m), &m.voxel_of, &m.voxels);
  }
  out.voxels = static_cast<int>(m.voxels.size());

  // 3. Ground.
  const Ground ground = FindGround(m.voxels, p.ground);
  out.ground_found = ground.found;
  if (ground.found) out.ground << ground.normal, ground.d;
  out.ground_inliers = ground.inliers;
  out.ransac_iterations = ground.iterations;

  // 4. Clusters of the rest; the tolerance grows with range as σ_Z does.
  const double noise_per_m2 = p.cluster.noise_k * p.cluster.disparity_noise_px / fb;  // k·σ_d/(f·B)
  const std::vector<std::vector<int>> clusters =
      p.cluster.use_pcl ? PclClusters(m.voxels, ground.is_ground, p.cluster, noise_per_m2)
                        : FindClusters(m.voxels, ground.is_ground, p.cluster, noise_per_m2);
  out.clusters = static_cast<int>(clusters.size());

  // 5.–7. Obstacles: clusters above the size, measured on their own points, corrected, zoned.
  std::vector<int> label(m.voxels.size(), -1);
  for (size_t c = 0; c < clusters.size(); ++c)
    for (int v : clusters[c]) label[static_cast<size_t>(v)] = static_cast<int>(c);
  std::vector<std::vector<int>> members(clusters.size());
  for (size_t i = 0; i < m.cloud.points.size(); ++i) {
    const int l = label[static_cast<size_t>(m.voxel_of[i])];
    if (l >= 0) members[static_cast<size_t>(l)].push_back(static_cast<int>(i));
  }
  for (size_t c = 0; c < clusters.size(); ++c) {
    if (static_cast<int>(clusters[c].size()) < p.obstacle.min_points) continue;
    DetectedObstacle o;
    o.voxels = static_cast<int>(clusters[c].size());
    if (!MeasureObstacle(m.cloud.points, members[c], ground, p.obstacle, &o)) continue;
    // The temporal spread at the obstacle: Δd = f·B·(1/Z − 1/Z_prev) of each of its samples
    // that held a depth in the frame before too.
    if (follows) {
      for (int i : members[c]) {
        const size_t k = static_cast<size_t>(m.cloud.sample_of[static_cast<size_t>(i)]);
        if (m.previous_depth[k] > 0.0f)
          m.temporal.Add(fb * (1.0 / m.cloud.depth_m[k] - 1.0 / m.previous_depth[k]));
      }
    }
    ApplyMargin(*m.scenario, p, sigma_d_px_, fb, &o);
    out.obstacles.push_back(o);
  }
  std::sort(out.obstacles.begin(), out.obstacles.end(),
            [](const DetectedObstacle& a, const DetectedObstacle& b) {
              return a.range_m < b.range_m;
            });
  // A blind frame clears nothing: its zone, and every obstacle's in it, is stop.
  out.zone = out.blind ? Zone::kStop : Zone::kClear;
  for (DetectedObstacle& o : out.obstacles) {
    if (out.blind) o.zone = Zone::kStop;
    out.zone = std::min(out.zone, o.zone);  // kStop < kSlow < kClear
  }
  m.previous_depth.swap(m.cloud.depth_m);
  m.has_previous = true;
  m.previous_index = index;
  return out;
}

}  // namespace depthbias::detect
