#include "metrics/panel_pixels.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <Eigen/Cholesky>

#include "common/select.h"

namespace depthbias::metrics {
namespace {

// The normal equations of an inverse-depth plane 1/Z = k·(x/z, y/z, 1) of pixels' means, each
// weighted by its samples, summed pixel after pixel. The rays are (x, y, 1): the normal matrix's
// six distinct sums are kept.
struct InverseDepthSums {
  double sw = 0, swx = 0, swy = 0, swxx = 0, swxy = 0, swyy = 0;
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  int used = 0;

  // weight_per_mean = weight / the pixel's mean depth.
  void Add(const Eigen::Vector3d& ray, double weight, double weight_per_mean) {
    const double w = weight, x = ray.x(), y = ray.y();
    sw += w;
    swx += w * x;
    swy += w * y;
    swxx += w * x * x;
    swxy += w * x * y;
    swyy += w * y * y;
    atb += weight_per_mean * ray;
    ++used;
  }
  // False when fewer than 3 pixels or a degenerate system.
  bool Solve(Plane* plane) const {
    if (used < 3) return false;
    Eigen::Matrix3d ata;
    ata << swxx, swxy, swx, swxy, swyy, swy, swx, swy, sw;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(ata);
    const Eigen::Vector3d k = ldlt.solve(atb);
    const double len = k.norm();
    if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-12) || !std::isfinite(len) ||
        !(len > 0))
      return false;
    plane->normal = -k / len;
    plane->offset_m = 1.0 / len;
    return true;
  }
};

// Fewer observed interior pixels than this: the first plane and the noise read every pixel.
constexpr std::size_t kMinInteriorPixels = 12;

// 1.4826 × the median of r (|disparity residual|·√n of the used pixels, reordered): σ_d of
// one sample.
double ScatterPx(std::vector<double>& r) {
  if (r.empty()) return 0.0;
  return 1.4826 * common::NthSmallest(r, r.size() / 2);
}

// The region's interior: its pixels at least a quarter of the bounding box's width (height) in
// from its left and right (top and bottom) sides, the central half of the panel's image each way.
// A region without a bounding box (RegionFromRectangle and RegionFromBox give one) has none.
std::vector<std::uint8_t> Interior(const PanelRegion& region) {
  std::vector<std::uint8_t> inner(region.pixels.size(), 0);
  const int u0 = region.u_min, u1 = region.u_max, v0 = region.v_min, v1 = region.v_max;
  if (region.width <= 0 || u1 < u0 || v1 < v0) return inner;
  const double qu = (u1 - u0 + 1) / 4.0, qv = (v1 - v0 + 1) / 4.0;
  for (std::size_t k = 0; k < region.pixels.size(); ++k) {
    const int u = static_cast<int>(region.pixels[k] % static_cast<std::uint32_t>(region.width));
    const int v = static_cast<int>(region.pixels[k] / static_cast<std::uint32_t>(region.width));
    inner[k] = u - u0 >= qu && u1 - u >= qu && v - v0 >= qv && v1 - v >= qv;
  }
  return inner;
}

}  // namespace

bool PanelPixelParams::IsValid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (!(baseline_m > 0) || !std::isfinite(baseline_m)) return fail("baseline_m must be positive");
  if (!(expected_subpixel_rms_px > 0) || !std::isfinite(expected_subpixel_rms_px))
    return fail("expected_subpixel_rms_px must be positive");
  if (!(sigma_k > 0) || !std::isfinite(sigma_k)) return fail("sigma_k must be positive");
  if (!(plane_distance_m >= 0) || !std::isfinite(plane_distance_m))
    return fail("plane_distance_m must be zero or positive");
  if (!(ground_distance_m >= 0) || !std::isfinite(ground_distance_m))
    return fail("ground_distance_m must be zero or positive");
  if (refit_iterations < 0 || refit_iterations > 100)
    return fail("refit_iterations must be in [0, 100]");
  if (pooled_frames < 0) return fail("pooled_frames must be >= 0");
  return true;
}

double DepartureLimitM(double plane_depth_m, std::uint32_t n, double focal_px,
                       double subpixel_rms_px, const PanelPixelParams& p) {
  const double sigma_z =
      plane_depth_m * plane_depth_m * subpixel_rms_px / (focal_px * p.baseline_m);
  return p.sigma_k * sigma_z / std::sqrt(static_cast<double>(n)) + p.plane_distance_m;
}

PixelClass ClassifyMeanDepth(const Eigen::Vector3d& ray, std::uint32_t n, double z,
                             double focal_px, double subpixel_rms_px, const Plane& plane,
                             const Plane* ground, const PanelPixelParams& p) {
  if (n == 0) return PixelClass::kHole;
  if (ground && ground->Distance(z * ray) < p.ground_distance_m) return PixelClass::kGround;
  const double zp = plane.DepthOnRay(ray);
  if (!std::isfinite(zp)) return PixelClass::kBehind;  // the ray misses the plane
  const double limit = DepartureLimitM(zp, n, focal_px, subpixel_rms_px, p);
  if (z - zp > limit) return PixelClass::kBehind;
  if (zp - z > limit) return PixelClass::kInFront;
  return PixelClass::kOnPlane;
}

bool FitPooledPlane(const camera::Intrinsics& in, const std::vector<std::uint32_t>& pixels,
                    const std::vector<PooledPixel>& pooled, double units, Plane* plane) {
  const std::size_t n = std::min(pixels.size(), pooled.size());
  const PixelNormalizer normalized(in);
  InverseDepthSums sums;
  for (std::size_t k = 0; k < n; ++k) {
    if (pooled[k].count == 0 || pooled[k].sum_counts == 0) continue;
    const Eigen::Vector2d r = normalized.OfIndex(pixels[k]);
    const double weight = pooled[k].count;
    sums.Add({r.x(), r.y(), 1.0}, weight,
             weight / (static_cast<double>(pooled[k].sum_counts) / pooled[k].count * units));
  }
  return sums.Solve(plane);
}

PanelPixels DecidePanelPixels(const camera::Intrinsics& in, const PanelRegion& region,
                              const std::vector<PooledPixel>& pooled, double units,
                              const Plane* ground, const PanelPixelParams& p) {
  PanelPixels out;
  const std::size_t n = region.pixels.size();
  const double fb = in.fx * p.baseline_m;
  // Each observed pixel's ray, mean depth and samples, and what does not change from one plane
  // to the next: the ground, √n, 1/√n, n/Z, f·B/Z. The first plane: every observed interior
  // pixel, each counted once (a textured background seen past the panel's edge gives many
  // samples a pixel where a hole-ridden panel gives few: weighted by its samples, a strip of it
  // would pull the first plane off the panel); then the pixels on it, each weighted by its
  // samples, until they no longer change. σ_d is read on the interior throughout.
  std::vector<Eigen::Vector3d> rays(n);
  std::vector<double> mean_m(n, 0.0), weight(n, 0.0);
  std::vector<std::uint8_t> observed(n, 0), on_ground(n, 0);
  std::vector<double> inv_sqrt_n(n, 0.0), sqrt_n(n, 0.0), n_per_z(n, 0.0), disparity(n, 0.0);
  const PixelNormalizer normalized(in);
  const std::vector<std::uint8_t> inner = Interior(region);
  std::size_t inner_observed = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector2d r = normalized.OfIndex(region.pixels[k]);
    rays[k] = {r.x(), r.y(), 1.0};
    if (!(k < pooled.size() && pooled[k].count > 0)) continue;
    weight[k] = pooled[k].count;
    mean_m[k] = static_cast<double>(pooled[k].sum_counts) / pooled[k].count * units;
    if (!(mean_m[k] > 0)) continue;
    observed[k] = 1;
    sqrt_n[k] = std::sqrt(weight[k]);
    inv_sqrt_n[k] = 1.0 / sqrt_n[k];
    n_per_z[k] = weight[k] / mean_m[k];
    disparity[k] = fb / mean_m[k];
    on_ground[k] = ground && ground->Distance(mean_m[k] * rays[k]) < p.ground_distance_m;
    inner_observed += inner[k];
  }
  // The interior reads the panel's noise and first plane; too few observed pixels there: all.
  const bool use_inner = inner_observed >= kMinInteriorPixels;
  InverseDepthSums first;
  for (std::size_t k = 0; k < n; ++k)
    if (observed[k] && (inner[k] || !use_inner)) first.Add(rays[k], 1.0, 1.0 / mean_m[k]);
  out.plane_ok = first.Solve(&out.plane);
  // ClassifyMeanDepth, with those precomputed, on the current plane's depth on each observed
  // pixel's ray (computed once a plane; NaN on the others).
  const double k_sigma = p.sigma_k / (fb);
  std::vector<double> plane_z(n, NAN);
  auto classify = [&](std::size_t k) {
    if (on_ground[k]) return PixelClass::kGround;
    const double zp = plane_z[k];
    if (!std::isfinite(zp)) return PixelClass::kBehind;
    const double limit =
        k_sigma * zp * zp * out.subpixel_rms_px * inv_sqrt_n[k] + p.plane_distance_m;
    if (mean_m[k] - zp > limit) return PixelClass::kBehind;
    if (zp - mean_m[k] > limit) return PixelClass::kInFront;
    return PixelClass::kOnPlane;
  };
  std::vector<std::uint8_t> on(n, 0);  // the pixels the current plane was fitted on
  std::vector<double> residual;
  residual.reserve(n);
  // plane_z stays that of out.plane wherever the loop ends: the classes below read it.
  for (int it = 0; out.plane_ok; ++it) {
    residual.clear();
    for (std::size_t k = 0; k < n; ++k) {
      if (!observed[k]) continue;
      const double zp = out.plane.DepthOnRay(rays[k]);
      plane_z[k] = zp;
      if (std::isfinite(zp) && (inner[k] || !use_inner))
        residual.push_back(std::fabs(disparity[k] - fb / zp) * sqrt_n[k]);
    }
    out.subpixel_rms_px = std::max(p.expected_subpixel_rms_px, ScatterPx(residual));
    if (it == p.refit_iterations) break;
    bool changed = it == 0;
    InverseDepthSums refit_sums;
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint8_t now = observed[k] && classify(k) == PixelClass::kOnPlane;
      changed = changed || now != on[k];
      on[k] = now;
      if (now) refit_sums.Add(rays[k], weight[k], n_per_z[k]);
    }
    if (!changed) break;  // the refit would give the same plane and σ
    Plane refit;
    if (!refit_sums.Solve(&refit)) break;
    out.plane = refit;
  }
  out.pixels.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const PixelClass c = !observed[k] ? PixelClass::kHole
                         : out.plane_ok ? classify(k)
                                        : PixelClass::kOnPlane;
    switch (c) {
      case PixelClass::kHole: ++out.holes; break;
      case PixelClass::kOnPlane: ++out.on_plane; break;
      case PixelClass::kBehind: ++out.behind; break;
      case PixelClass::kInFront: ++out.in_front; break;
      case PixelClass::kGround: ++out.ground; break;
    }
    if (c == PixelClass::kHole || c == PixelClass::kOnPlane) out.pixels.push_back(region.pixels[k]);
  }
  return out;
}

PanelRegion WithPixels(const PanelRegion& region, std::vector<std::uint32_t> pixels) {
  PanelRegion out = region;
  out.pixels = std::move(pixels);
  return out;
}

}  // namespace depthbias::metrics
