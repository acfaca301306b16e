#include "detect/detector.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include <Eigen/Eigenvalues>

// PCL's templates are instantiated here from its headers (as in lib/panel), so that only
// libpcl_common is linked and start-up stays short.
#define PCL_NO_PRECOMPILE
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/ransac.h>
#include <pcl/sample_consensus/sac_model_perpendicular_plane.h>
#include <pcl/search/kdtree.h>

#include "common/seeded_ransac.h"

namespace depthbias::detect {
namespace {

constexpr double kDegToRad = M_PI / 180.0;
constexpr double kRadToDeg = 180.0 / M_PI;

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

using common::CountingRansac;
using common::Seeded;

inline std::uint64_t Mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// Voxel grid: integer cube coordinates packed in 64 bits, an open-addressing hash table from
// key to voxel, centroids accumulated in one pass.
class VoxelGrid {
 public:
  // voxel_of[i]: the voxel of point i; centroids: one per occupied cube, in first-seen order.
  void Build(const std::vector<Eigen::Vector3f>& points, float leaf_m, std::vector<int>* voxel_of,
             std::vector<Eigen::Vector3f>* centroids) {
    size_t size = 1024;
    while (size < 2 * points.size()) size *= 2;
    if (keys_.size() != size) {
      keys_.assign(size, kEmpty);
      slots_.assign(size, -1);
    } else {
      std::fill(keys_.begin(), keys_.end(), kEmpty);
    }
    const std::uint64_t mask = size - 1;
    const float inv = 1.0f / leaf_m;
    voxel_of->resize(points.size());
    centroids->clear();
    counts_.clear();
    for (size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector3f& p = points[i];
      // 21 bits per axis, offset so that ±1e6 cubes are positive.
      const auto cell = [inv](float v) {
        return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(v * inv)) +
                                          (1 << 20)) & 0x1FFFFF;
      };
      const std::uint64_t key = cell(p.x()) | cell(p.y()) << 21 | cell(p.z()) << 42;
      std::uint64_t h = Mix64(key) & mask;
      while (keys_[h] != kEmpty && keys_[h] != key) h = (h + 1) & mask;
      if (keys_[h] == kEmpty) {
        keys_[h] = key;
        slots_[h] = static_cast<int>(centroids->size());
        centroids->push_back(Eigen::Vector3f::Zero());
        counts_.push_back(0);
      }
      const int v = slots_[h];
      (*voxel_of)[i] = v;
      (*centroids)[static_cast<size_t>(v)] += p;
      ++counts_[static_cast<size_t>(v)];
    }
    for (size_t v = 0; v < centroids->size(); ++v)
      (*centroids)[v] /= static_cast<float>(counts_[v]);
  }

 private:
  static constexpr std::uint64_t kEmpty = ~0ULL;
  std::vector<std::uint64_t> keys_;
  std::vector<int> slots_;
  std::vector<int> counts_;
};

// Total least squares plane n·p + d = 0 of points (PCA), or false when degenerate.
bool FitPlane(const std::vector<Eigen::Vector3d>& pts, Eigen::Vector3d* n, double* d) {
  if (pts.size() < 3) return false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= static_cast<double>(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) cov += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  if (eig.info() != Eigen::Success) return false;
  *n = eig.eigenvectors().col(0);
  *d = -n->dot(mean);
  return true;
}

double Median(std::vector<double>* v) {
  const size_t mid = v->size() / 2;
  std::nth_element(v->begin(), v->begin() + static_cast<std::ptrdiff_t>(mid), v->end());
  double m = (*v)[mid];
  if (v->size() % 2 == 0 && mid > 0) {
    m = 0.5 * (m + *std::max_element(v->begin(), v->begin() + static_cast<std::ptrdiff_t>(mid)));
  }
  return m;
}

}  // namespace

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
  // One sample pixel per stride block: its index in the frame and its ray at Z = 1.
  std::vector<std::uint32_t> pixel;
  std::vector<Eigen::Vector3f> ray;
  std::vector<float> ray_norm;
  // Per-frame buffers.
  std::vector<Eigen::Vector3f> points;
  std::vector<int> sample_of;  // the sample (index in `pixel`) of each point
  // The depth Z of every sample in this frame and the one before (0: none), for the temporal
  // spread at the obstacles.
  std::vector<float> depth, previous_depth;
  bool has_previous = false;
  std::uint64_t previous_index = 0;
  TemporalNoise temporal;
  std::vector<int> voxel_of;
  std::vector<Eigen::Vector3f> voxels;
  VoxelGrid grid;
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
  const int s = params.cloud.stride_px;
  for (int v = s / 2; v < intrinsics.height; v += s) {
    for (int u = s / 2; u < intrinsics.width; u += s) {
      const Eigen::Vector2d xy = camera::PixelToNormalized(intrinsics, Eigen::Vector2d(u, v));
      impl_->pixel.push_back(static_cast<std::uint32_t>(v * intrinsics.width + u));
      impl_->ray.emplace_back(static_cast<float>(xy.x()), static_cast<float>(xy.y()), 1.0f);
      impl_->ray_norm.push_back(static_cast<float>(std::sqrt(xy.squaredNorm() + 1.0)));
    }
  }
}

ObstacleDetector::~ObstacleDetector() = default;

void ObstacleDetector::SetDisparityNoisePx(double sigma_px) {
  if (!(sigma_px > 0.0) || !std::isfinite(sigma_px))
    throw std::invalid_argument("disparity noise must be > 0 px");
  sigma_d_px_ = sigma_px;
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

  // 1. Cloud: one pixel per block, deprojected along its precomputed ray.
  m.points.clear();
  m.sample_of.clear();
  m.depth.assign(m.pixel.size(), 0.0f);
  const float units = static_cast<float>(frame.depth_units_m);
  const float min_r = static_cast<float>(p.cloud.min_range_m);
  const float max_r = static_cast<float>(p.cloud.max_range_m);
  const std::uint16_t* counts = frame.counts.data();
  for (size_t k = 0; k < m.pixel.size(); ++k) {
    const std::uint16_t c = counts[m.pixel[k]];
    if (c == 0 || c == 0xFFFF) continue;  // no depth, or a count at full scale
    const float z = c * units;
    const float r = z * m.ray_norm[k];
    if (r < min_r || r > max_r) continue;
    m.points.push_back(z * m.ray[k]);
    m.sample_of.push_back(static_cast<int>(k));
    m.depth[k] = z;
  }
  out.cloud_points = static_cast<int>(m.points.size());
  out.samples = static_cast<int>(m.pixel.size());
  out.valid_pct = out.samples > 0 ? 100.0 * out.cloud_points / out.samples : 0.0;
  out.blind = !(out.valid_pct >= p.cloud.min_valid_pct) || out.samples == 0;
  out.zone = out.blind ? Zone::kStop : Zone::kClear;

  // 2. Voxel grid.
  m.grid.Build(m.points, static_cast<float>(p.voxel.leaf_m), &m.voxel_of, &m.voxels);
  const int nv = static_cast<int>(m.voxels.size());
  out.voxels = nv;
  out.success = true;
  out.disparity_noise_px = sigma_d_px_;
  // This frame's depths become the previous ones once it is done.
  struct KeepDepths {
    Impl& m;
    std::uint64_t index;
    ~KeepDepths() {
      std::swap(m.depth, m.previous_depth);
      m.has_previous = true;
      m.previous_index = index;
    }
  } keep{m, index};
  const bool follows = m.has_previous && index == m.previous_index + 1 &&
                       m.previous_depth.size() == m.depth.size();
  const double fb = m.intrinsics.fx * p.baseline_m;  // f·B [px·m]
  if (nv == 0) return out;
  Cloud::Ptr cloud(new Cloud);
  cloud->resize(static_cast<size_t>(nv));
  for (int i = 0; i < nv; ++i) {
    const Eigen::Vector3f& q = m.voxels[static_cast<size_t>(i)];
    (*cloud)[static_cast<size_t>(i)] = pcl::PointXYZ(q.x(), q.y(), q.z());
  }

  // 3. Ground: RANSAC plane whose normal is within max_tilt_deg of the camera's up axis.
  std::vector<char> is_ground(static_cast<size_t>(nv), 0);
  Eigen::Vector3d up(0, -1, 0);
  double ground_d = 0.0;
  if (p.ground.enabled && nv >= 3) {
    pcl::Indices all(static_cast<size_t>(nv));
    std::iota(all.begin(), all.end(), 0);
    auto sac = std::make_shared<
        Seeded<pcl::SampleConsensusModelPerpendicularPlane<pcl::PointXYZ>>>(cloud, all,
                                                                            p.ground.seed);
    sac->setAxis(Eigen::Vector3f(0, 1, 0));
    sac->setEpsAngle(p.ground.max_tilt_deg * kDegToRad);
    CountingRansac ransac(sac, p.ground.distance_m);
    ransac.setMaxIterations(p.ground.max_iterations);
    ransac.setProbability(p.ground.probability);
    if (ransac.computeModel()) {
      out.ransac_iterations = ransac.iterations();
      pcl::Indices inliers;
      ransac.getInliers(inliers);
      Eigen::VectorXf coeff;
      ransac.getModelCoefficients(coeff);
      Eigen::Vector3d n(coeff.size() == 4 ? coeff[0] : 0, coeff.size() == 4 ? coeff[1] : 0,
                        coeff.size() == 4 ? coeff[2] : 0);
      double d = coeff.size() == 4 ? coeff[3] : 0.0;
      const double len = n.norm();
      if (len > 0 && inliers.size() >= p.ground.min_fraction * nv) {
        n /= len;
        d /= len;
        // Least-squares refinement on the points within the band.
        for (int it = 0; it < p.ground.refine_iterations; ++it) {
          std::vector<Eigen::Vector3d> band;
          for (int i = 0; i < nv; ++i) {
            const Eigen::Vector3d q = m.voxels[static_cast<size_t>(i)].cast<double>();
            if (std::fabs(n.dot(q) + d) < p.ground.distance_m) band.push_back(q);
          }
          Eigen::Vector3d n2;
          double d2;
          if (!FitPlane(band, &n2, &d2)) break;
          if (n2.dot(n) < 0) {
            n2 = -n2;
            d2 = -d2;
          }
          n = n2;
          d = d2;
        }
        if (d < 0) {  // the camera on the + side
          n = -n;
          d = -d;
        }
        out.ground_found = true;
        out.ground << n, d;
        up = n;
        ground_d = d;
        for (int i = 0; i < nv; ++i) {
          // The ground and whatever lies below it.
          if (n.dot(m.voxels[static_cast<size_t>(i)].cast<double>()) + d < p.ground.distance_m) {
            is_ground[static_cast<size_t>(i)] = 1;
            ++out.ground_inliers;
          }
        }
      }
    }
  }

  // 4. Euclidean clusters of the rest; the tolerance grows with range as σ_Z does.
  std::vector<int> rest;  // voxel indices
  for (int i = 0; i < nv; ++i)
    if (!is_ground[static_cast<size_t>(i)]) rest.push_back(i);
  std::vector<int> label(static_cast<size_t>(nv), -1);
  std::vector<std::vector<int>> clusters;
  if (!rest.empty()) {
    Cloud::Ptr obstacles(new Cloud);
    obstacles->resize(rest.size());
    for (size_t j = 0; j < rest.size(); ++j)
      (*obstacles)[j] = (*cloud)[static_cast<size_t>(rest[j])];
    pcl::search::KdTree<pcl::PointXYZ> tree(false);
    tree.setInputCloud(obstacles);
    const double noise = p.cluster.noise_k * p.cluster.disparity_noise_px /
                         (m.intrinsics.fx * p.baseline_m);  // k·σ_d/(f·B)
    std::vector<char> seen(rest.size(), 0);
    pcl::Indices found;
    std::vector<float> dist2;
    std::vector<int> queue;
    for (size_t start = 0; start < rest.size(); ++start) {
      if (seen[start]) continue;
      seen[start] = 1;
      queue.assign(1, static_cast<int>(start));
      for (size_t head = 0; head < queue.size(); ++head) {
        const pcl::PointXYZ& q = (*obstacles)[static_cast<size_t>(queue[head])];
        const double r2 = static_cast<double>(q.x) * q.x + static_cast<double>(q.y) * q.y +
                          static_cast<double>(q.z) * q.z;
        const double tol = p.cluster.base_tolerance_m + noise * r2;  // + k·σ_Z(r)
        tree.radiusSearch(q, tol, found, dist2);
        for (const auto j : found) {
          if (seen[static_cast<size_t>(j)]) continue;
          seen[static_cast<size_t>(j)] = 1;
          queue.push_back(j);
        }
      }
      if (static_cast<int>(queue.size()) < p.cluster.min_points) continue;
      std::vector<int> members;
      for (int j : queue) {
        members.push_back(rest[static_cast<size_t>(j)]);
        label[static_cast<size_t>(rest[static_cast<size_t>(j)])] =
            static_cast<int>(clusters.size());
      }
      clusters.push_back(std::move(members));
    }
  }
  out.clusters = static_cast<int>(clusters.size());

  // 5. Obstacles: clusters above the size, measured on their own points.
  std::vector<std::vector<int>> members(clusters.size());
  for (size_t i = 0; i < m.points.size(); ++i) {
    const int l = label[static_cast<size_t>(m.voxel_of[i])];
    if (l >= 0) members[static_cast<size_t>(l)].push_back(static_cast<int>(i));
  }
  const model::ScenarioModel& scenario = *m.scenario;
  std::vector<double> ranges, depths;
  for (size_t c = 0; c < clusters.size(); ++c) {
    if (static_cast<int>(clusters[c].size()) < p.obstacle.min_points || members[c].empty())
      continue;
    double h_lo = 1e30, h_hi = -1e30, a_lo = 1e30, a_hi = -1e30;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    ranges.clear();
    depths.clear();
    for (int i : members[c]) {
      const Eigen::Vector3d q = m.points[static_cast<size_t>(i)].cast<double>();
      sum += q;
      ranges.push_back(q.norm());
      depths.push_back(q.z());
      const double h = up.dot(q) + ground_d;
      h_lo = std::min(h_lo, h);
      h_hi = std::max(h_hi, h);
      const double a = std::atan2(q.x(), q.z());
      a_lo = std::min(a_lo, a);
      a_hi = std::max(a_hi, a);
    }
    DetectedObstacle o;
    o.voxels = static_cast<int>(clusters[c].size());
    o.points = static_cast<int>(members[c].size());
    o.height_m = h_hi - h_lo;
    if (o.height_m < p.obstacle.min_height_m) continue;
    // The temporal spread at the obstacle: Δd = f·B·(1/Z − 1/Z_prev) of each of its samples
    // that held a depth in the frame before too.
    if (follows) {
      for (int i : members[c]) {
        const size_t k = static_cast<size_t>(m.sample_of[static_cast<size_t>(i)]);
        if (m.previous_depth[k] > 0.0f)
          m.temporal.Add(fb * (1.0 / m.depth[k] - 1.0 / m.previous_depth[k]));
      }
    }
    o.centroid_m = sum / static_cast<double>(members[c].size());
    o.azimuth_deg = std::atan2(o.centroid_m.x(), o.centroid_m.z()) * kRadToDeg;
    o.off_axis_deg =
        std::atan2(std::hypot(o.centroid_m.x(), o.centroid_m.y()), o.centroid_m.z()) * kRadToDeg;
    o.range_m = Median(&ranges);
    o.depth_m = Median(&depths);
    o.width_m = (a_hi - a_lo) * o.range_m;
    // The model (the same call correct_depth makes) turns the median depth Z of the points at
    // the centroid's off-axis angle α into the range of the target's centre. Its σ is that of a
    // recording's median; this frame's median of n points adds its own noise,
    // 1.2533·σ_Z(Z)/√n with σ_Z = Z²·σ_d/(f·B) (the median's efficiency for a normal).
    o.corrected_range_m = scenario.CorrectedM(o.depth_m, o.off_axis_deg);
    const double model_std = scenario.PredictiveStdM(o.depth_m, o.off_axis_deg);
    const double reading_std =
        1.2533 * o.depth_m * o.depth_m * sigma_d_px_ / fb / std::sqrt(o.points);
    o.std_m = std::hypot(model_std, reading_std);
    // Never farther than the camera saw it (unless asked): min(raw, corrected − k·σ). A safe
    // range that is not a number stays one (its zone is stop).
    const double model_safe_m = o.corrected_range_m - p.k * o.std_m;
    o.safe_range_m = p.safe_beyond_raw || std::isnan(model_safe_m)
                         ? model_safe_m
                         : std::min(o.range_m, model_safe_m);
    o.near_guarded = scenario.NearGuarded(o.depth_m, o.off_axis_deg);
    o.zone = ZoneFor(o.safe_range_m, p.zones);
    out.obstacles.push_back(o);
  }
  std::sort(out.obstacles.begin(), out.obstacles.end(),
            [](const DetectedObstacle& a, const DetectedObstacle& b) {
              return a.range_m < b.range_m;
            });
  for (DetectedObstacle& o : out.obstacles) {
    if (out.blind) o.zone = Zone::kStop;
    out.zone = std::min(out.zone, o.zone);  // kStop < kSlow < kClear
  }
  return out;
}

}  // namespace depthbias::detect
