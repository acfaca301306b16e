// Stages 1, 5 and 6 (stages.h): a frame's samples as points, an obstacle measured on its
// points, its corrected range and margin.
#include <algorithm>
#include <cmath>

#include "detect/stages.h"

namespace depthbias::detect {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

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

SampleRays MakeSampleRays(const camera::Intrinsics& intrinsics, int stride_px) {
  SampleRays r;
  const int s = stride_px;
  for (int v = s / 2; v < intrinsics.height; v += s) {
    for (int u = s / 2; u < intrinsics.width; u += s) {
      const Eigen::Vector2d xy = camera::PixelToNormalized(intrinsics, Eigen::Vector2d(u, v));
      r.pixel.push_back(static_cast<std::uint32_t>(v * intrinsics.width + u));
      r.ray.emplace_back(static_cast<float>(xy.x()), static_cast<float>(xy.y()), 1.0f);
      r.ray_norm.push_back(static_cast<float>(std::sqrt(xy.squaredNorm() + 1.0)));
    }
  }
  return r;
}

void BuildCloud(const records::DepthFrame& frame, const SampleRays& rays,
                const CloudParams& params, SampledCloud* out) {
  out->points.clear();
  out->sample_of.clear();
  out->depth_m.assign(rays.pixel.size(), 0.0f);
  const float units = static_cast<float>(frame.depth_units_m);
  const float min_r = static_cast<float>(params.min_range_m);
  const float max_r = static_cast<float>(params.max_range_m);
  const std::uint16_t* counts = frame.counts.data();
  for (size_t k = 0; k < rays.pixel.size(); ++k) {
    const std::uint16_t c = counts[rays.pixel[k]];
    if (c == 0 || c == 0xFFFF) continue;  // no depth, or a count at full scale
    const float z = c * units;
    const float r = z * rays.ray_norm[k];
    if (r < min_r || r > max_r) continue;
    out->points.push_back(z * rays.ray[k]);
    out->sample_of.push_back(static_cast<int>(k));
    out->depth_m[k] = z;
  }
  out->samples = static_cast<int>(rays.pixel.size());
  out->valid_pct =
      out->samples > 0 ? 100.0 * static_cast<double>(out->points.size()) / out->samples : 0.0;
}

bool IsBlind(const SampledCloud& cloud, const CloudParams& params) {
  return cloud.samples == 0 || !(cloud.valid_pct >= params.min_valid_pct);
}

bool MeasureObstacle(const std::vector<Eigen::Vector3f>& points, const std::vector<int>& members,
                     const Ground& ground, const ObstacleParams& params, DetectedObstacle* o) {
  if (members.empty()) return false;
  double h_lo = 1e30, h_hi = -1e30, a_lo = 1e30, a_hi = -1e30;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::vector<double> ranges, depths;
  ranges.reserve(members.size());
  depths.reserve(members.size());
  for (int i : members) {
    const Eigen::Vector3d q = points[static_cast<size_t>(i)].cast<double>();
    sum += q;
    ranges.push_back(q.norm());
    depths.push_back(q.z());
    const double h = ground.normal.dot(q) + ground.d;
    h_lo = std::min(h_lo, h);
    h_hi = std::max(h_hi, h);
    const double a = std::atan2(q.x(), q.z());
    a_lo = std::min(a_lo, a);
    a_hi = std::max(a_hi, a);
  }
  o->points = static_cast<int>(members.size());
  o->height_m = h_hi - h_lo;
  if (o->height_m < params.min_height_m) return false;
  o->centroid_m = sum / static_cast<double>(members.size());
  o->azimuth_deg = std::atan2(o->centroid_m.x(), o->centroid_m.z()) * kRadToDeg;
  o->off_axis_deg =
      std::atan2(std::hypot(o->centroid_m.x(), o->centroid_m.y()), o->centroid_m.z()) * kRadToDeg;
  o->range_m = Median(&ranges);
  o->depth_m = Median(&depths);
  o->width_m = (a_hi - a_lo) * o->range_m;
  return true;
}

void ApplyMargin(const model::ScenarioModel& scenario, const DetectorParams& params,
                 double disparity_noise_px, double focal_baseline_px_m, DetectedObstacle* o) {
  // The model (the same call correct_depth makes) turns the median depth Z of the points at
  // the centroid's off-axis angle α into the range of the target's centre. Its σ is that of a
  // recording's median; this frame's median of n points adds its own noise,
  // 1.2533·σ_Z(Z)/√n with σ_Z = Z²·σ_d/(f·B) (the median's efficiency for a normal).
  o->corrected_range_m = scenario.CorrectedM(o->depth_m, o->off_axis_deg);
  const double model_std = scenario.PredictiveStdM(o->depth_m, o->off_axis_deg);
  const double reading_std = 1.2533 * o->depth_m * o->depth_m * disparity_noise_px /
                             focal_baseline_px_m / std::sqrt(o->points);
  o->std_m = std::hypot(model_std, reading_std);
  // Never farther than the camera saw it (unless asked): min(raw, corrected − k·σ). A safe
  // range that is not a number stays one (its zone is stop).
  const double model_safe_m = o->corrected_range_m - params.k * o->std_m;
  o->safe_range_m = params.safe_beyond_raw || std::isnan(model_safe_m)
                        ? model_safe_m
                        : std::min(o->range_m, model_safe_m);
  o->near_guarded = scenario.NearGuarded(o->depth_m, o->off_axis_deg);
  o->zone = ZoneFor(o->safe_range_m, params.zones);
}

}  // namespace depthbias::detect
