#include "panel/measure.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

namespace depthbias::panel {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr std::size_t kRangeBins = 1u << 17;  // range up to 131071 depth units

// Value of the histogram at rank (0-based) among its total.
std::size_t RankValue(const std::vector<std::uint64_t>& hist, std::uint64_t rank) {
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < hist.size(); ++i) {
    seen += hist[i];
    if (seen > rank) return i;
  }
  return hist.size() - 1;
}

// Median of a histogram of integers (mean of the two middle values for an even count).
double HistMedian(const std::vector<std::uint64_t>& hist, std::uint64_t total) {
  if (total == 0) return std::nan("");
  const std::size_t a = RankValue(hist, (total - 1) / 2);
  const std::size_t b = RankValue(hist, total / 2);
  return 0.5 * (static_cast<double>(a) + static_cast<double>(b));
}

}  // namespace

RegionMeasurer::RegionMeasurer(const RayTable* rays, PanelRegion region, double baseline_m)
    : rays_(rays),
      region_(std::move(region)),
      baseline_m_(baseline_m),
      sums_(region_.pixels.size()),
      depth_hist_(1u << 16, 0),
      range_hist_(kRangeBins, 0) {}

void RegionMeasurer::Add(const records::DepthFrame& frame) {
  if (frames_ == 0) {
    depth_units_m_ = frame.depth_units_m;
  } else if (frame.depth_units_m != depth_units_m_) {
    mixed_units_ = true;
  }
  ++frames_;
  const double units = frame.depth_units_m;
  const std::uint16_t* counts = frame.counts.data();
  bool any = false;
  for (std::size_t k = 0; k < region_.pixels.size(); ++k) {
    const std::uint32_t i = region_.pixels[k];
    const std::uint16_t c = counts[i];
    if (c == 0) continue;
    any = true;
    const double z = c * units;
    PixelSums& s = sums_[k];
    ++s.n;
    s.z += z;
    s.z2 += z * z;
    const double inv = 1.0 / z;
    s.inv += inv;
    s.inv2 += inv * inv;
    ++depth_hist_[c];
    const std::size_t r = std::min<std::size_t>(
        kRangeBins - 1, static_cast<std::size_t>(std::lround(c * rays_->Norm(i))));
    ++range_hist_[r];
  }
  if (any) ++frames_with_depth_;
}

MeasureResult RegionMeasurer::Finish(const Eigen::Vector3d& center_m,
                                     records::PanelMetrics* m) const {
  MeasureResult res;
  res.frames = frames_;
  res.frames_with_depth = frames_with_depth_;
  m->region_px = static_cast<double>(region_.pixels.size());
  m->frames = static_cast<double>(frames_with_depth_);
  if (region_.pixels.empty()) {
    res.why_not = "the panel region holds no pixel";
    return res;
  }
  if (frames_ == 0) {
    res.why_not = "no frame to measure";
    return res;
  }
  if (mixed_units_) {
    res.why_not = "depth units change within the recording";
    return res;
  }
  // Pooled moments: every sample is p = Z·r with r fixed per pixel, so Σp = Σ_pixels r·ΣZ and
  // Σp·pᵀ = Σ_pixels r·rᵀ·ΣZ².
  PlaneMoments mom;
  double sum_z = 0;
  std::uint64_t n = 0;
  std::vector<double> temporal;
  temporal.reserve(region_.pixels.size());
  for (std::size_t k = 0; k < region_.pixels.size(); ++k) {
    const PixelSums& s = sums_[k];
    if (s.n == 0) continue;
    const Eigen::Vector3d r = rays_->Ray(region_.pixels[k]);
    mom.weight += s.n;
    mom.sum += r * s.z;
    mom.sum_outer += r * r.transpose() * s.z2;
    sum_z += s.z;
    n += s.n;
    if (s.n >= 2) {
      const double mean = s.z / s.n;
      temporal.push_back(std::sqrt(std::max(0.0, (s.z2 - s.n * mean * mean) / (s.n - 1))));
    }
  }
  res.samples = n;
  const double total = static_cast<double>(region_.pixels.size()) * frames_;
  m->hole_rate_pct = 100.0 * (1.0 - n / total);
  m->valid_pct = 100.0 - m->hole_rate_pct;
  if (n == 0) {
    res.why_not = "no valid depth in the panel region";
    return res;
  }
  m->mean_m = sum_z / n;
  m->median_m = HistMedian(depth_hist_, n) * depth_units_m_;
  m->range_m = HistMedian(range_hist_, n) * depth_units_m_;
  if (!temporal.empty()) {
    std::nth_element(temporal.begin(), temporal.begin() + temporal.size() / 2, temporal.end());
    m->temporal_std_m = temporal[temporal.size() / 2];
  }
  res.plane = FitPlane(mom);
  if (res.plane.ok) m->plane_std_m = res.plane.rms_m;
  // Inverse-depth plane: normal equations of 1/Z = k·a, a = (x/z, y/z, 1), one row per sample.
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < region_.pixels.size(); ++k) {
    const PixelSums& s = sums_[k];
    if (s.n == 0) continue;
    const Eigen::Vector3d a = rays_->Ray(region_.pixels[k]);
    ata += s.n * a * a.transpose();
    atb += s.inv * a;
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(ata);
  const Eigen::Vector3d k = ldlt.solve(atb);
  const double len = k.norm();
  if (ldlt.info() == Eigen::Success && ldlt.rcond() > 1e-12 && std::isfinite(len) && len > 0) {
    // n·(Z·a) + d = 0 ⇔ 1/Z = −(n/d)·a, so n = −k/|k| and d = 1/|k| (d > 0: n faces the camera).
    res.disparity_plane_ok = true;
    res.disparity_plane.normal = -k / len;
    res.disparity_plane.offset_m = 1.0 / len;
    const Plane& pl = res.disparity_plane;
    m->normal_tilt_deg = std::acos(std::min(1.0, std::fabs(pl.normal.z()))) * kRadToDeg;
    // Subpixel RMS (Depth Quality Tool): D = f·B/Z of each sample against DP = f·B/ZP of the
    // same pixel's ray on the fitted plane; Σ(D − DP)² = (fB)²·(Σ1/Z² − 2/ZP·Σ1/Z + n/ZP²).
    const double fb = rays_->intrinsics().fx * baseline_m_;
    double sq = 0;
    std::uint64_t used = 0;
    for (std::size_t j = 0; j < region_.pixels.size(); ++j) {
      const PixelSums& s = sums_[j];
      if (s.n == 0) continue;
      const double zp = pl.DepthOnRay(rays_->Ray(region_.pixels[j]));
      if (!std::isfinite(zp)) continue;
      const double ip = 1.0 / zp;
      sq += std::max(0.0, s.inv2 - 2.0 * ip * s.inv + s.n * ip * ip);
      used += s.n;
    }
    if (used > 0) m->subpixel_rms_px = fb * std::sqrt(sq / used);
  }
  // Direction of the panel centre: azimuth + right, elevation + up (camera y points down).
  m->azimuth_deg = std::atan2(center_m.x(), center_m.z()) * kRadToDeg;
  m->elevation_deg = std::atan2(-center_m.y(), std::hypot(center_m.x(), center_m.z())) * kRadToDeg;
  res.ok = true;
  return res;
}

}  // namespace depthbias::panel
