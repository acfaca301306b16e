#include "metrics/region_metrics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Cholesky>

#include "common/select.h"

namespace depthbias::metrics {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr std::size_t kRangeBins = 1u << 17;  // range up to 131071 depth units

// Value of the histogram at rank (0-based) among its total: hist[i] counts value lo + i − 1
// ([0] is not a value's).
std::size_t RankValue(const std::vector<std::uint64_t>& hist, std::size_t lo,
                      std::uint64_t rank) {
  std::uint64_t seen = 0;
  for (std::size_t i = 1; i < hist.size(); ++i) {
    seen += hist[i];
    if (seen > rank) return lo + i - 1;
  }
  return lo + hist.size() - 2;
}

// Median of a histogram of integers: the mean of the two middle values for an even count.
double HistMedian(const std::vector<std::uint64_t>& hist, std::size_t lo, std::uint64_t total) {
  if (total == 0) return records::PanelMetrics::kMissing;
  const std::size_t a = RankValue(hist, lo, (total - 1) / 2);
  const std::size_t b = RankValue(hist, lo, total / 2);
  return 0.5 * (static_cast<double>(a) + static_cast<double>(b));
}

// std::lround of a product c·|ray| >= 0 (exact: a float plus ½ is exact in double).
inline std::size_t RoundRange(float x) {
  return static_cast<std::size_t>(static_cast<long>(static_cast<double>(x) + 0.5));
}

// The same vector of bins over the values [new_lo, new_hi] instead of those from lo (bin 0
// kept in place).
void Rebase(std::vector<std::uint64_t>* bins, std::size_t lo, std::size_t new_lo,
            std::size_t new_hi) {
  std::vector<std::uint64_t> out(new_hi - new_lo + 2, 0);
  if (!bins->empty()) {
    out[0] = (*bins)[0];
    std::copy(bins->begin() + 1, bins->end(), out.begin() + 1 + (lo - new_lo));
  }
  bins->swap(out);
}

// Median of values: the mean of the two middle ones for an even count.
double Median(std::vector<double> v) {
  if (v.empty()) return records::PanelMetrics::kMissing;
  const std::size_t mid = v.size() / 2;
  double m = common::NthSmallest(v, mid);
  if (v.size() % 2 == 0) m = 0.5 * (m + common::NthSmallest(v, mid - 1));
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
      pixels_(region.pixels) {
  std::string why;
  if (!params.IsValid(&why)) throw std::invalid_argument("metrics kernel: " + why);
  if (region.width != intrinsics.width || region.height != intrinsics.height)
    throw std::invalid_argument("metrics kernel: the region's image size is not the intrinsics'");
  rays_.reserve(pixels_.size());
  range_per_count_.reserve(pixels_.size());
  const PixelNormalizer normalized(intrinsics);
  for (std::uint32_t i : pixels_) {
    const Eigen::Vector2d r = normalized.OfIndex(i);
    rays_.emplace_back(r.x(), r.y(), 1.0);
    range_per_count_.push_back(static_cast<float>(std::sqrt(1.0 + r.squaredNorm())));
  }
  if (!range_per_count_.empty()) {
    const auto [lo, hi] = std::minmax_element(range_per_count_.begin(), range_per_count_.end());
    min_range_per_count_ = *lo;
    max_range_per_count_ = *hi;
  }
  sums_.resize(pixels_.size());
  valid_.resize(pixels_.size());
  pairs_.resize(pixels_.size());
  previous_.resize(pixels_.size(), 0);
}

void RegionMetrics::AddFrame(const records::DepthFrame& frame) {
  const std::uint16_t* counts = frame.counts.data();
  gathered_.resize(pixels_.size());  // here, not made for callers that give counts themselves
  for (std::size_t k = 0; k < pixels_.size(); ++k) gathered_[k] = counts[pixels_[k]];
  AddRegionCounts(gathered_.data(), frame.depth_units_m);
}

void RegionMetrics::Cover(std::size_t c_lo, std::size_t c_hi, std::size_t r_lo,
                          std::size_t r_hi) {
  if (count_lo_ == 0 || c_lo < count_lo_ || c_hi > count_lo_ + terms_.size() - 2) {
    const std::size_t lo = count_lo_ == 0 ? c_lo : std::min(c_lo, count_lo_);
    const std::size_t hi = count_lo_ == 0 ? c_hi : std::max(c_hi, count_lo_ + terms_.size() - 2);
    Rebase(&depth_hist_, count_lo_, lo, hi);
    terms_.assign(hi - lo + 2, CountTerms{});
    for (std::size_t c = lo; c <= hi; ++c) {
      CountTerms& t = terms_[c - lo + 1];
      t.z = static_cast<double>(c) * depth_units_m_;
      t.z2 = t.z * t.z;
      t.inv = 1.0 / t.z;
      t.inv2 = t.inv * t.inv;
      t.per_count = 1.0 / static_cast<double>(c);
    }
    count_lo_ = lo;
  }
  if (range_lo_ == 0 || r_lo < range_lo_ || r_hi > range_lo_ + range_hist_.size() - 2) {
    const std::size_t lo = range_lo_ == 0 ? r_lo : std::min(r_lo, range_lo_);
    const std::size_t hi =
        range_lo_ == 0 ? r_hi : std::max(r_hi, range_lo_ + range_hist_.size() - 2);
    Rebase(&range_hist_, range_lo_, lo, hi);
    range_lo_ = lo;
  }
}

void RegionMetrics::AddRegionCounts(const std::uint16_t* counts, double units) {
  if (frames_ == 0) {
    depth_units_m_ = units;
  } else if (units != depth_units_m_) {
    mixed_units_ = true;
  }
  const std::size_t n = pixels_.size();
  // The frame's smallest and largest valid count (c − 1 wraps a hole to the largest).
  std::uint16_t least_minus_1 = 0xFFFF, most = 0;
  for (std::size_t k = 0; k < n; ++k) {
    least_minus_1 = std::min<std::uint16_t>(least_minus_1, counts[k] - 1);
    most = std::max(most, counts[k]);
  }
  const bool any = most > 0;
  // A change of depth units is refused in Finish, which then uses none of the sums.
  if (any && !mixed_units_) {
    // Ranges lie between the extreme counts times the extreme |ray| (products and rounding
    // are monotonic).
    const std::size_t least = static_cast<std::size_t>(least_minus_1) + 1;
    const std::size_t r_lo = std::min<std::size_t>(
        kRangeBins - 1, RoundRange(static_cast<int>(least) * min_range_per_count_));
    const std::size_t r_hi = std::min<std::size_t>(
        kRangeBins - 1, RoundRange(static_cast<int>(most) * max_range_per_count_));
    Cover(least, most, std::max<std::size_t>(r_lo, 1), r_hi);
  }
  // The frame's valid pixels, and those also valid in the frame before, listed without a
  // branch (holes come and go at random: a branch per pixel would be mispredicted often).
  std::uint32_t* const valid = valid_.data();
  std::uint32_t* const pairs = pairs_.data();
  std::size_t n_valid = 0, n_pairs = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const bool c = counts[k] != 0;
    valid[n_valid] = static_cast<std::uint32_t>(k);
    n_valid += c;
    pairs[n_pairs] = static_cast<std::uint32_t>(k);
    n_pairs += c & (previous_[k] != 0);
  }
  // Temporal disparity noise: pixels valid in this frame and the one before (the first frame
  // has none before it). Every count of the frame before is covered by terms_.
  if (frames_ > 0 && !mixed_units_) {
    const double fb_units = intrinsics_.fx * params_.baseline_m / units;  // f·B/Z = fb_units/c
    const CountTerms* const terms = terms_.data();
    const std::size_t base = count_lo_ - 1;
    const std::uint16_t* const previous = previous_.data();
    temporal_noise_.AddEach(n_pairs, [&](std::size_t j) {
      const std::size_t k = pairs[j];
      return fb_units * (terms[counts[k] - base].per_count - terms[previous[k] - base].per_count);
    });
  }
  std::copy(counts, counts + n, previous_.begin());
  ++frames_;
  if (!any) return;
  ++frames_with_depth_;
  if (mixed_units_) return;
  const CountTerms* const terms = terms_.data();
  std::uint64_t* const depth_hist = depth_hist_.data();
  std::uint64_t* const range_hist = range_hist_.data();
  const float* const range_per_count = range_per_count_.data();
  PixelSums* const sums = sums_.data();
  const std::size_t c_base = count_lo_ - 1, r_base = range_lo_ - 1;
  for (std::size_t j = 0; j < n_valid; ++j) {
    const std::size_t k = valid[j];
    const std::uint16_t c = counts[k];
    const CountTerms& ct = terms[c - c_base];
    PixelSums& s = sums[k];
    ++s.n;
    s.z += ct.z;
    s.z2 += ct.z2;
    s.inv += ct.inv;
    s.inv2 += ct.inv2;
    ++depth_hist[c - c_base];
    const std::size_t r =
        std::min<std::size_t>(kRangeBins - 1, RoundRange(c * range_per_count[k]));
    ++range_hist[r - r_base];
  }
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
  // The sums as scalars: r·ΣZ, r·rᵀ·ΣZ², n·r·rᵀ and ΣZ⁻¹·r, entry by entry, the symmetric ones
  // once (r_z = 1). ata's off-diagonal is (n·y)·x, the lower triangle the LDLT reads.
  double w = 0, m0 = 0, m1 = 0, m2 = 0;                         // mom.weight, mom.sum
  double o00 = 0, o01 = 0, o02 = 0, o11 = 0, o12 = 0, o22 = 0;  // mom.sum_outer
  double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;  // ata
  double b0 = 0, b1 = 0, b2 = 0;                                // atb
  for (std::size_t k = 0; k < pixels_.size(); ++k) {
    const PixelSums& s = sums_[k];
    if (s.n == 0) continue;
    const Eigen::Vector3d& r = rays_[k];
    sampled_rays.push_back(r);
    const double x = r.x(), y = r.y(), z = r.z(), sn = s.n;
    w += sn;
    m0 += x * s.z;
    m1 += y * s.z;
    m2 += z * s.z;
    o00 += x * x * s.z2;
    o01 += x * y * s.z2;
    o02 += x * z * s.z2;
    o11 += y * y * s.z2;
    o12 += y * z * s.z2;
    o22 += z * z * s.z2;
    a00 += sn * x * x;
    a01 += sn * y * x;
    a02 += sn * x * z;
    a11 += sn * y * y;
    a12 += sn * y * z;
    a22 += sn * z * z;
    b0 += s.inv * x;
    b1 += s.inv * y;
    b2 += s.inv * z;
    sum_z += s.z;
    n += s.n;
    if (s.n >= 2) {
      const double mean = s.z / s.n;
      temporal.push_back(std::sqrt(std::max(0.0, (s.z2 - s.n * mean * mean) / (s.n - 1))));
    }
  }
  mom.weight = w;
  mom.sum = {m0, m1, m2};
  mom.sum_outer << o00, o01, o02, o01, o11, o12, o02, o12, o22;
  ata << a00, a01, a02, a01, a11, a12, a02, a12, a22;
  atb = {b0, b1, b2};
  res.samples = n;
  const double total = static_cast<double>(pixels_.size()) * static_cast<double>(frames_);
  m->valid_pct = 100.0 * static_cast<double>(n) / total;
  m->hole_rate_pct = 100.0 - m->valid_pct;
  if (n == 0) {
    res.message = "no valid depth in the panel region";
    return res;
  }
  m->mean_m = sum_z / static_cast<double>(n);
  m->median_m = HistMedian(depth_hist_, count_lo_, n) * depth_units_m_;
  m->range_m = HistMedian(range_hist_, range_lo_, n) * depth_units_m_;
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
