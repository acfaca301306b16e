#include "metrics/region_metrics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Cholesky>

namespace depthbias::metrics {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr std::size_t kDepthBins = 1u << 16;  // every 16-bit depth count
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

// Median of a histogram of integers: the mean of the two middle values for an even count.
double HistMedian(const std::vector<std::uint64_t>& hist, std::uint64_t total) {
  if (total == 0) return records::PanelMetrics::kMissing;
  const std::size_t a = RankValue(hist, (total - 1) / 2);
  const std::size_t b = RankValue(hist, total / 2);
  return 0.5 * (static_cast<double>(a) + static_cast<double>(b));
}

// Median of values: the mean of the two middle ones for an even count.
double Median(std::vector<double> v) {
  if (v.empty()) return records::PanelMetrics::kMissing;
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  double m = v[mid];
  if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + mid));
  return m;
}

}  // namespace

bool KernelParams::IsValid(std::string* why) const {
  if (!(baseline_m > 0) || !std::isfinite(baseline_m)) {
    *why = "baseline_m must be positive";
    return false;
  }
  if (!(region_margin_px >= 0) || !std::isfinite(region_margin_px)) {
    *why = "region_margin_px must be zero or positive";
    return false;
  }
  if (min_noise_pairs < 1) {
    *why = "min_noise_pairs must be >= 1";
    return false;
  }
  return true;
}

RegionMetrics::RegionMetrics(const camera::Intrinsics& intrinsics, const PanelRegion& region,
                             const KernelParams& params)
    : intrinsics_(intrinsics),
      params_(params),
      pixels_(region.pixels),
      depth_hist_(kDepthBins, 0),
      range_hist_(kRangeBins, 0) {
  std::string why;
  if (!params.IsValid(&why)) throw std::invalid_argument("metrics kernel: " + why);
  if (region.width != intrinsics.width || region.height != intrinsics.height)
    throw std::invalid_argument("metrics kernel: the region's image size is not the intrinsics'");
  rays_.reserve(pixels_.size());
  range_per_count_.reserve(pixels_.size());
  for (std::uint32_t i : pixels_) {
    const Eigen::Vector2d r = camera::PixelToNormalized(
        intrinsics, {static_cast<double>(i % intrinsics.width),
                     static_cast<double>(i / intrinsics.width)});
    rays_.emplace_back(r.x(), r.y(), 1.0);
    range_per_count_.push_back(static_cast<float>(std::sqrt(1.0 + r.squaredNorm())));
  }
  sums_.resize(pixels_.size());
  gathered_.resize(pixels_.size());
  previous_.resize(pixels_.size(), 0);
}

void RegionMetrics::AddFrame(const records::DepthFrame& frame) {
  const std::uint16_t* counts = frame.counts.data();
  for (std::size_t k = 0; k < pixels_.size(); ++k) gathered_[k] = counts[pixels_[k]];
  AddRegionCounts(gathered_.data(), frame.depth_units_m);
}

void RegionMetrics::AddRegionCounts(const std::uint16_t* counts, double units) {
  if (frames_ == 0) {
    depth_units_m_ = units;
  } else if (units != depth_units_m_) {
    mixed_units_ = true;
  }
  // Temporal disparity noise: pixels valid in this frame and the one before (the first frame
  // has none before it; a change of depth units is refused in Finish anyway).
  if (frames_ > 0 && !mixed_units_) {
    const double fb_units = intrinsics_.fx * params_.baseline_m / units;  // f·B/Z = fb_units/c
    for (std::size_t k = 0; k < pixels_.size(); ++k) {
      const std::uint16_t c = counts[k], p = previous_[k];
      if (c == 0 || p == 0) continue;
      temporal_noise_.Add(fb_units * (1.0 / c - 1.0 / p));
    }
  }
  std::copy(counts, counts + pixels_.size(), previous_.begin());
  ++frames_;
  bool any = false;
  for (std::size_t k = 0; k < pixels_.size(); ++k) {
    const std::uint16_t c = counts[k];
    if (c == 0) continue;
    any = true;
    const double z = c * units;
    const double inv = 1.0 / z;
    PixelSums& s = sums_[k];
    ++s.n;
    s.z += z;
    s.z2 += z * z;
    s.inv += inv;
    s.inv2 += inv * inv;
    ++depth_hist_[c];
    const std::size_t r = std::min<std::size_t>(
        kRangeBins - 1, static_cast<std::size_t>(std::lround(c * range_per_count_[k])));
    ++range_hist_[r];
  }
  if (any) ++frames_with_depth_;
}

KernelResult RegionMetrics::Finish(const Eigen::Vector3d& up_m, records::PanelMetrics* m) const {
  KernelResult res;
  res.frames = frames_;
  res.frames_with_depth = frames_with_depth_;
  m->region_px = static_cast<double>(pixels_.size());
  m->frames = static_cast<double>(frames_with_depth_);
  if (pixels_.empty()) {
    res.message = "the panel region holds no pixel";
    return res;
  }
  if (frames_ == 0) {
    res.message = "no frame to measure";
    return res;
  }
  if (mixed_units_) {
    res.message = "depth units change within the recording";
    return res;
  }
  // Pooled moments: every sample is p = Z·r with r fixed per pixel, so Σp = Σ_pixels r·ΣZ and
  // Σp·pᵀ = Σ_pixels r·rᵀ·ΣZ². Inverse-depth plane: normal equations of 1/Z = k·a, a = r.
  PlaneMoments mom;
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  double sum_z = 0;
  std::uint64_t n = 0;
  std::vector<double> temporal;
  temporal.reserve(pixels_.size());
  std::vector<Eigen::Vector3d> sampled_rays;
  sampled_rays.reserve(pixels_.size());
  for (std::size_t k = 0; k < pixels_.size(); ++k) {
    const PixelSums& s = sums_[k];
    if (s.n == 0) continue;
    const Eigen::Vector3d& r = rays_[k];
    sampled_rays.push_back(r);
    mom.weight += s.n;
    mom.sum += r * s.z;
    mom.sum_outer += r * r.transpose() * s.z2;
    ata += s.n * r * r.transpose();
    atb += s.inv * r;
    sum_z += s.z;
    n += s.n;
    if (s.n >= 2) {
      const double mean = s.z / s.n;
      temporal.push_back(std::sqrt(std::max(0.0, (s.z2 - s.n * mean * mean) / (s.n - 1))));
    }
  }
  res.samples = n;
  const double total = static_cast<double>(pixels_.size()) * static_cast<double>(frames_);
  m->valid_pct = 100.0 * static_cast<double>(n) / total;
  m->hole_rate_pct = 100.0 - m->valid_pct;
  if (n == 0) {
    res.message = "no valid depth in the panel region";
    return res;
  }
  m->mean_m = sum_z / static_cast<double>(n);
  m->median_m = HistMedian(depth_hist_, n) * depth_units_m_;
  m->range_m = HistMedian(range_hist_, n) * depth_units_m_;
  m->temporal_std_m = Median(std::move(temporal));
  res.noise_pairs = temporal_noise_.pairs();
  if (res.noise_pairs >= params_.min_noise_pairs) m->sigma_d_px = temporal_noise_.SigmaPx();
  res.plane = FitPlane(mom);
  if (res.plane.ok) m->plane_std_m = res.plane.rms_m;

  const Eigen::LDLT<Eigen::Matrix3d> ldlt(ata);
  const Eigen::Vector3d kv = ldlt.solve(atb);
  const double len = kv.norm();
  if (ldlt.info() == Eigen::Success && ldlt.rcond() > 1e-12 && std::isfinite(len) && len > 0) {
    // n·(Z·a) + d = 0 ⇔ 1/Z = −(n/d)·a, so n = −k/|k| and d = 1/|k| (d > 0: n faces the camera).
    res.disparity_plane_ok = true;
    res.disparity_plane.normal = -kv / len;
    res.disparity_plane.offset_m = 1.0 / len;
    const Plane& pl = res.disparity_plane;
    m->normal_tilt_deg = std::acos(std::min(1.0, std::fabs(pl.normal.z()))) * kRadToDeg;
    // Subpixel RMS (Depth Quality Tool): D = f·B/Z of each sample against DP = f·B/ZP of the
    // same pixel's ray on the fitted plane; Σ(D − DP)² = (fB)²·(Σ1/Z² − 2/ZP·Σ1/Z + n/ZP²).
    const double fb = intrinsics_.fx * params_.baseline_m;
    double sq = 0;
    std::uint64_t used = 0;
    for (std::size_t k = 0; k < pixels_.size(); ++k) {
      const PixelSums& s = sums_[k];
      if (s.n == 0) continue;
      const double zp = pl.DepthOnRay(rays_[k]);
      if (!std::isfinite(zp)) continue;
      const double ip = 1.0 / zp;
      sq += std::max(0.0, s.inv2 - 2.0 * ip * s.inv + s.n * ip * ip);
      used += s.n;
    }
    if (used > 0) m->subpixel_rms_px = fb * std::sqrt(sq / static_cast<double>(used));
    // Tilt's standard error: Cov(k) = s²·(AᵀA)⁻¹, s² the residual variance in inverse depth,
    // propagated through tilt(k) = acos(|k_z|/|k|) by central differences.
    if (used > 3) {
      const double s2 = sq / static_cast<double>(used - 3);
      const Eigen::Matrix3d cov = s2 * ldlt.solve(Eigen::Matrix3d::Identity());
      auto tilt = [](const Eigen::Vector3d& v) {
        return std::acos(std::min(1.0, std::fabs(v.z()) / v.norm()));
      };
      Eigen::Vector3d grad;
      for (int a = 0; a < 3; ++a) {
        const double h = 1e-6 * len;
        Eigen::Vector3d hi = kv, lo = kv;
        hi[a] += h;
        lo[a] -= h;
        grad[a] = (tilt(hi) - tilt(lo)) / (2 * h);
      }
      const double var = grad.dot(cov * grad);
      if (var >= 0 && std::isfinite(var)) res.tilt_sigma_deg = std::sqrt(var) * kRadToDeg;
    }
    // Extent and direction of the panel: the sampled pixels on the plane.
    res.rectangle_ok = RectangleFromRays(intrinsics_, pl, up_m, sampled_rays,
                                         1.0 + 2.0 * params_.region_margin_px, &res.rectangle);
    if (res.rectangle_ok) {
      const Eigen::Vector3d& c = res.rectangle.center_m;
      m->panel_width_m = res.rectangle.width_m;
      m->panel_height_m = res.rectangle.height_m;
      m->azimuth_deg = std::atan2(c.x(), c.z()) * kRadToDeg;
      m->elevation_deg = std::atan2(-c.y(), std::hypot(c.x(), c.z())) * kRadToDeg;
    }
  }
  res.success = true;
  return res;
}

}  // namespace depthbias::metrics
