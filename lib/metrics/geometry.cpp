#include "metrics/geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

namespace depthbias::metrics {

RayTable::RayTable(const camera::Intrinsics& intrinsics) : intrinsics_(intrinsics) {
  const std::size_t n = static_cast<std::size_t>(intrinsics.width) * intrinsics.height;
  xy_.resize(2 * n);
  norm_.resize(n);
  for (int v = 0; v < intrinsics.height; ++v) {
    for (int u = 0; u < intrinsics.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * intrinsics.width + u;
      const Eigen::Vector2d r = camera::PixelToNormalized(intrinsics, {u, v});
      xy_[2 * i] = static_cast<float>(r.x());
      xy_[2 * i + 1] = static_cast<float>(r.y());
      norm_[i] = static_cast<float>(std::sqrt(1.0 + r.squaredNorm()));
    }
  }
}

PixelNormalizer::PixelNormalizer(const camera::Intrinsics& intrinsics)
    : intrinsics_(intrinsics), distorted_(!camera::IsDistortionZero(intrinsics)) {
  if (distorted_) return;
  thread_local camera::Intrinsics last;
  thread_local std::shared_ptr<const Tables> last_tables;
  auto same = [](const camera::Intrinsics& a, const camera::Intrinsics& b) {
    return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy &&
           a.ppx == b.ppx && a.ppy == b.ppy && a.model == b.model && a.coeffs == b.coeffs;
  };
  if (!last_tables || !same(last, intrinsics)) {
    auto t = std::make_shared<Tables>();
    t->x.resize(static_cast<std::size_t>(std::max(intrinsics.width, 0)));
    t->y.resize(static_cast<std::size_t>(std::max(intrinsics.height, 0)));
    for (int u = 0; u < intrinsics.width; ++u)
      t->x[static_cast<std::size_t>(u)] = camera::PixelToNormalized(intrinsics, {u, 0}).x();
    for (int v = 0; v < intrinsics.height; ++v)
      t->y[static_cast<std::size_t>(v)] = camera::PixelToNormalized(intrinsics, {0, v}).y();
    last = intrinsics;
    last_tables = std::move(t);
  }
  tables_ = last_tables;
  x_ = tables_->x.data();
  y_ = tables_->y.data();
}

void PlaneMoments::Add(const Eigen::Vector3d& p, double w) {
  weight += w;
  sum += w * p;
  sum_outer += w * p * p.transpose();
}

PlaneFit FitPlane(const PlaneMoments& m) {
  PlaneFit fit;
  if (!(m.weight > 0)) return fit;
  const Eigen::Vector3d c = m.sum / m.weight;
  Eigen::Matrix3d cov = m.sum_outer / m.weight - c * c.transpose();
  cov = 0.5 * (cov + cov.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  if (eig.info() != Eigen::Success) return fit;
  // Eigenvalues ascending: the first eigenvector is the normal, and the middle one must be
  // well above it for the points to span a plane.
  if (!(eig.eigenvalues()(1) > 0)) return fit;
  Eigen::Vector3d n = eig.eigenvectors().col(0).normalized();
  if (n.dot(-c) < 0) n = -n;  // toward the camera at the origin
  fit.ok = true;
  fit.plane.normal = n;
  fit.plane.offset_m = -n.dot(c);
  fit.centroid_m = c;
  fit.rms_m = std::sqrt(std::max(0.0, eig.eigenvalues()(0)));
  return fit;
}

std::array<Eigen::Vector3d, 4> PanelRectangle::Corners() const {
  const Eigen::Vector3d w = 0.5 * width_m * axis_width;
  const Eigen::Vector3d h = 0.5 * height_m * axis_up;
  return {center_m - w - h, center_m + w - h, center_m + w + h, center_m - w + h};
}

Eigen::Vector2d PixelFootprint(const camera::Intrinsics& in, const PanelRectangle& rect) {
  const Eigen::Vector2d c = camera::Project(in, rect.center_m);
  auto at = [&](double du, double dv) {
    const Eigen::Vector2d r = camera::PixelToNormalized(in, {c.x() + du, c.y() + dv});
    Eigen::Vector2d st(0, 0);
    rect.PlaneCoordinates({r.x(), r.y(), 1.0}, &st);
    return st;
  };
  // Jacobian of the plane coordinates over one pixel step in u and in v.
  const Eigen::Vector2d du = at(0.5, 0) - at(-0.5, 0);
  const Eigen::Vector2d dv = at(0, 0.5) - at(0, -0.5);
  return {std::fabs(du.x()) + std::fabs(dv.x()), std::fabs(du.y()) + std::fabs(dv.y())};
}

namespace {

// Extent along one axis with isolated strays removed: walks in from each end while the gap to
// the next value exceeds max_gap, dropping at most 2 % of the values per end.
void RobustExtent(std::vector<double> v, double max_gap, double* lo, double* hi) {
  const std::size_t n = v.size();
  const std::size_t cap = std::max<std::size_t>(1, n / 50);
  // Only the cap + 2 smallest and largest values are looked at: those two ends in order (the
  // same values a full sort puts there), the middle left unsorted.
  const std::size_t end = cap + 2;
  if (n <= 4 * end) {
    std::sort(v.begin(), v.end());
  } else {
    std::nth_element(v.begin(), v.begin() + end, v.end());
    std::sort(v.begin(), v.begin() + end);
    std::nth_element(v.begin() + end, v.end() - end, v.end());
    std::sort(v.end() - end, v.end());
  }
  std::size_t a = 0, b = n - 1;
  while (a < cap && a + 1 < b && v[a + 1] - v[a] > max_gap) ++a;
  while (n - 1 - b < cap && b > a + 1 && v[b] - v[b - 1] > max_gap) --b;
  *lo = v[a];
  *hi = v[b];
}

void FinishRegion(PanelRegion* r) {
  if (!std::is_sorted(r->pixels.begin(), r->pixels.end()))  // mostly drawn in order already
    std::sort(r->pixels.begin(), r->pixels.end());
  if (r->pixels.empty()) return;
  r->u_min = r->width;
  r->v_min = r->height;
  // Row by row (the pixels are sorted): a division per row, not per pixel.
  std::uint32_t row_start = 0, row_end = 0;
  int v = 0;
  for (std::uint32_t i : r->pixels) {
    if (i >= row_end) {
      v = static_cast<int>(i / r->width);
      row_start = static_cast<std::uint32_t>(v) * static_cast<std::uint32_t>(r->width);
      row_end = row_start + static_cast<std::uint32_t>(r->width);
    }
    const int u = static_cast<int>(i - row_start);
    r->u_min = std::min(r->u_min, u);
    r->u_max = std::max(r->u_max, u);
    r->v_min = std::min(r->v_min, v);
    r->v_max = std::max(r->v_max, v);
  }
}

}  // namespace

// In-plane axes of a panel plane: up is the ground's up direction (or the camera's) projected
// onto the plane, width = up × normal (to the image's right for a panel facing the camera).
bool PanelAxes(const Plane& plane, const Eigen::Vector3d& up_hint, Eigen::Vector3d* axis_w,
               Eigen::Vector3d* axis_up) {
  Eigen::Vector3d up = up_hint - up_hint.dot(plane.normal) * plane.normal;
  if (up.norm() < 0.3) return false;  // plane close to horizontal: not a standing panel
  up.normalize();
  *axis_up = up;
  *axis_w = up.cross(plane.normal).normalized();
  return true;
}

PanelRegion RegionFromRectangle(const camera::Intrinsics& in, const PanelRectangle& rect,
                                double margin_px) {
  PanelRegion region;
  region.width = in.width;
  region.height = in.height;
  const Eigen::Vector2d foot = PixelFootprint(in, rect);
  const double half_w = 0.5 * rect.width_m - margin_px * foot.x();
  const double half_h = 0.5 * rect.height_m - margin_px * foot.y();
  double umin = in.width, umax = -1, vmin = in.height, vmax = -1;
  for (const Eigen::Vector3d& corner : rect.Corners()) {
    if (!(corner.z() > 0)) continue;
    const Eigen::Vector2d px = camera::Project(in, corner);
    region.outline_px.push_back(px);
    umin = std::min(umin, px.x());
    umax = std::max(umax, px.x());
    vmin = std::min(vmin, px.y());
    vmax = std::max(vmax, px.y());
  }
  if (region.outline_px.size() != 4 || half_w <= 0 || half_h <= 0) return region;
  const int u0 = std::max(0, static_cast<int>(std::floor(umin)) - 2);
  const int u1 = std::min(in.width - 1, static_cast<int>(std::ceil(umax)) + 2);
  const int v0 = std::max(0, static_cast<int>(std::floor(vmin)) - 2);
  const int v1 = std::min(in.height - 1, static_cast<int>(std::ceil(vmax)) + 2);
  const PixelNormalizer normalized(in);
  auto inside = [&](int u, int v) {
    const Eigen::Vector2d r = normalized(u, v);
    Eigen::Vector2d st;
    return rect.PlaneCoordinates({r.x(), r.y(), 1.0}, &st) && std::fabs(st.x()) <= half_w &&
           std::fabs(st.y()) <= half_h;
  };
  // Row by row: a row's pixels inside a convex quadrilateral are one run, and the next row's
  // run starts and ends near this one's, so each run's ends are found by walking from the last
  // row's ends (testing only the pixels on the way) and the pixels between them are inside. A
  // row whose run is not found that way is scanned whole.
  int lo = -1, hi = -1;  // the last row's run; lo < 0: none
  for (int v = v0; v <= v1; ++v) {
    if (lo >= 0) {
      if (inside(lo, v)) {
        while (lo > u0 && inside(lo - 1, v)) --lo;
      } else {
        while (lo < hi && !inside(lo + 1, v)) ++lo;
        lo = lo < hi ? lo + 1 : -1;  // past the last run: scan the row
      }
    }
    if (lo >= 0) {
      if (hi < lo) hi = lo;
      if (inside(hi, v)) {
        while (hi < u1 && inside(hi + 1, v)) ++hi;
      } else {
        while (hi > lo && !inside(hi - 1, v)) --hi;
        --hi;
      }
    } else {
      for (lo = u0; lo <= u1 && !inside(lo, v); ++lo) {
      }
      if (lo > u1) {
        lo = -1;
        continue;
      }
      for (hi = u1; !inside(hi, v); --hi) {
      }
    }
    const std::uint32_t row = static_cast<std::uint32_t>(v) * static_cast<std::uint32_t>(in.width);
    for (int u = lo; u <= hi; ++u) region.pixels.push_back(row + static_cast<std::uint32_t>(u));
  }
  FinishRegion(&region);
  return region;
}

PanelRegion RegionFromBox(int width, int height, double u0, double v0, double u1, double v1) {
  PanelRegion region;
  region.width = width;
  region.height = height;
  region.outline_px = {{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}};
  const int a = std::max(0, static_cast<int>(std::ceil(u0)));
  const int b = std::min(width, static_cast<int>(std::ceil(u1)));
  const int c = std::max(0, static_cast<int>(std::ceil(v0)));
  const int d = std::min(height, static_cast<int>(std::ceil(v1)));
  for (int v = c; v < d; ++v)
    for (int u = a; u < b; ++u)
      region.pixels.push_back(static_cast<std::uint32_t>(v * width + u));
  FinishRegion(&region);
  return region;
}

bool RectangleFromPixels(const RayTable& rays, const Plane& plane, const Eigen::Vector3d& up_hint,
                         const std::vector<std::uint32_t>& pixels, double footprint_px,
                         PanelRectangle* rect) {
  std::vector<Eigen::Vector3d> ray_list;
  ray_list.reserve(pixels.size());
  for (std::uint32_t i : pixels) ray_list.push_back(rays.Ray(i));
  return RectangleFromRays(rays.intrinsics(), plane, up_hint, ray_list, footprint_px, rect);
}

bool RectangleFromRays(const camera::Intrinsics& intrinsics, const Plane& plane,
                       const Eigen::Vector3d& up_hint, const std::vector<Eigen::Vector3d>& rays,
                       double footprint_px, PanelRectangle* rect) {
  if (rays.size() < 3) return false;
  PanelRectangle r;
  r.plane = plane;
  if (!PanelAxes(plane, up_hint, &r.axis_width, &r.axis_up)) return false;
  // Provisional centre: the plane point on the mean ray.
  Eigen::Vector3d mean_ray = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& ray : rays) mean_ray += ray;
  mean_ray /= static_cast<double>(rays.size());
  const double zc = plane.DepthOnRay(mean_ray);
  if (!std::isfinite(zc)) return false;
  r.center_m = zc * mean_ray;
  std::vector<double> s, t;
  s.reserve(rays.size());
  t.reserve(rays.size());
  Eigen::Vector2d st;
  for (const Eigen::Vector3d& ray : rays) {
    if (!r.PlaneCoordinates(ray, &st)) continue;
    s.push_back(st.x());
    t.push_back(st.y());
  }
  if (s.size() < 3) return false;
  r.width_m = r.height_m = 1.0;  // any size: only the footprint near the centre is needed
  const Eigen::Vector2d foot = PixelFootprint(intrinsics, r) * footprint_px;
  double s0, s1, t0, t1;
  RobustExtent(s, 3.0 * foot.x(), &s0, &s1);
  RobustExtent(t, 3.0 * foot.y(), &t0, &t1);
  r.center_m += 0.5 * (s0 + s1) * r.axis_width + 0.5 * (t0 + t1) * r.axis_up;
  r.width_m = s1 - s0 + foot.x();
  r.height_m = t1 - t0 + foot.y();
  *rect = r;
  return true;
}

}  // namespace depthbias::metrics
