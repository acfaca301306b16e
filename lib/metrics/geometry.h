#pragma once
// Geometry shared by panel detection, the metrics kernel and the simulator: per-pixel rays
// (deprojection done once per recording), planes and their least-squares fit from moments, the
// panel rectangle, and the one definition of the panel's image region.

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include <Eigen/Core>


#include "camera/intrinsics.h"

namespace depthbias::metrics {

// Ray of every pixel at Z = 1: point_m = depth_m · ray(u, v) (camera::Deproject semantics).
class RayTable {
 public:
  RayTable() = default;
  explicit RayTable(const camera::Intrinsics& intrinsics);
  const camera::Intrinsics& intrinsics() const { return intrinsics_; }
  int width() const { return intrinsics_.width; }
  int height() const { return intrinsics_.height; }
  // (x/z, y/z) of pixel index i = v·width + u.
  float x(std::size_t i) const { return xy_[2 * i]; }
  float y(std::size_t i) const { return xy_[2 * i + 1]; }
  Eigen::Vector3d Ray(std::size_t i) const { return {xy_[2 * i], xy_[2 * i + 1], 1.0}; }
  // |ray|: range_m = depth_m · Norm(i).
  float Norm(std::size_t i) const { return norm_[i]; }

 private:
  camera::Intrinsics intrinsics_;
  std::vector<float> xy_;
  std::vector<float> norm_;
};

// camera::PixelToNormalized of whole pixels (u, v), the same values: without distortion one
// division per column and per row of the image instead of two per pixel.
class PixelNormalizer {
 public:
  explicit PixelNormalizer(const camera::Intrinsics& intrinsics);
  Eigen::Vector2d operator()(int u, int v) const {
    if (distorted_) return camera::PixelToNormalized(intrinsics_, {u, v});
    return {x_[static_cast<std::size_t>(u)], y_[static_cast<std::size_t>(v)]};
  }
  // The same of pixel index i = v·width + u.
  Eigen::Vector2d OfIndex(std::uint32_t i) const {
    const int w = intrinsics_.width;
    return (*this)(static_cast<int>(i % w), static_cast<int>(i / w));
  }

 private:
  struct Tables {
    std::vector<double> x, y;  // per column, per row
  };
  camera::Intrinsics intrinsics_;
  bool distorted_ = false;
  // The last camera's tables of this thread, shared (the metrics build one normalizer per
  // region, thousands a run, of one camera).
  std::shared_ptr<const Tables> tables_;
  const double* x_ = nullptr;
  const double* y_ = nullptr;
};

// Plane n·p + d = 0 with |n| = 1, n oriented toward the camera (d > 0 for a plane in front).
struct Plane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset_m = 0.0;
  double Distance(const Eigen::Vector3d& p) const { return normal.dot(p) + offset_m; }
  // Depth Z at which the ray (x/z, y/z, 1) meets the plane; NaN when parallel or behind.
  // (Inline: the metrics call it per pixel.)
  double DepthOnRay(const Eigen::Vector3d& ray) const {
    // n·(Z·r) + d = 0  →  Z = −d / (n·r).
    const double nr = normal.dot(ray);
    if (std::fabs(nr) < 1e-12) return std::numeric_limits<double>::quiet_NaN();
    const double z = -offset_m / nr;
    return z > 0 ? z : std::numeric_limits<double>::quiet_NaN();
  }
};

// Sums for a least-squares plane: Σw, Σw·p, Σw·p·pᵀ.
struct PlaneMoments {
  double weight = 0.0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sum_outer = Eigen::Matrix3d::Zero();
  void Add(const Eigen::Vector3d& p, double w = 1.0);
};

struct PlaneFit {
  bool ok = false;
  Plane plane;
  Eigen::Vector3d centroid_m = Eigen::Vector3d::Zero();
  double rms_m = 0.0;  // RMS orthogonal distance of the points to the plane (√λ_min)
};
// Total least squares (PCA) plane of the moments; normal turned toward the camera.
PlaneFit FitPlane(const PlaneMoments& moments);

// The panel as a rectangle on its plane: centre, in-plane axes (width to the image's right,
// height upward) and size.
struct PanelRectangle {
  Plane plane;
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_width = Eigen::Vector3d::UnitX();
  Eigen::Vector3d axis_up = -Eigen::Vector3d::UnitY();
  double width_m = 0.0;
  double height_m = 0.0;
  // Corners: bottom-left, bottom-right, top-right, top-left (as seen from the camera).
  std::array<Eigen::Vector3d, 4> Corners() const;
  // In-plane coordinates (along width, along up) of the point where ray meets the plane,
  // relative to the centre; false when the ray misses the plane.
  bool PlaneCoordinates(const Eigen::Vector3d& ray, Eigen::Vector2d* st) const {
    const double z = plane.DepthOnRay(ray);
    if (!std::isfinite(z)) return false;
    const Eigen::Vector3d q = z * ray - center_m;
    *st = {q.dot(axis_width), q.dot(axis_up)};
    return true;
  }
};

// The pixels a region covers, as sorted pixel indices (v·width + u), and its outline.
struct PanelRegion {
  int width = 0;   // image size [px]
  int height = 0;
  std::vector<std::uint32_t> pixels;
  std::vector<Eigen::Vector2d> outline_px;  // polygon, image coordinates
  int u_min = 0, v_min = 0, u_max = -1, v_max = -1;  // bounding box (inclusive)
  std::size_t size() const { return pixels.size(); }
};

// The panel's image region, one definition for panel_extract and the simulator: pixels whose
// centre ray (deprojected with the intrinsics, in double precision) meets the rectangle shrunk by
// margin_px pixel footprints per side (footprint at the rectangle's centre).
PanelRegion RegionFromRectangle(const camera::Intrinsics& intrinsics, const PanelRectangle& rect,
                                double margin_px);
// Pixels of an image-aligned box [u0, u1) × [v0, v1), clipped to the image.
PanelRegion RegionFromBox(int width, int height, double u0, double v0, double u1, double v1);

// Rectangle bounding the given pixels on the plane: in-plane axes from up_hint (the ground's or
// the camera's up) projected onto the plane, extents from the pixels' rays meeting the plane
// (isolated strays left out) plus half of footprint_px pixels' footprint on each side. False
// for fewer than 3 pixels or a plane close to horizontal.
bool RectangleFromPixels(const RayTable& rays, const Plane& plane, const Eigen::Vector3d& up_hint,
                         const std::vector<std::uint32_t>& pixels, double footprint_px,
                         PanelRectangle* rect);
// The same from the pixels' rays (x/z, y/z, 1).
bool RectangleFromRays(const camera::Intrinsics& intrinsics, const Plane& plane,
                       const Eigen::Vector3d& up_hint, const std::vector<Eigen::Vector3d>& rays,
                       double footprint_px, PanelRectangle* rect);

// In-plane axes of a standing panel: up is up_hint (the ground's or the camera's up) projected
// onto the plane, width = up × normal (to the image's right for a panel facing the camera).
// False for a plane close to horizontal.
bool PanelAxes(const Plane& plane, const Eigen::Vector3d& up_hint, Eigen::Vector3d* axis_width,
               Eigen::Vector3d* axis_up);

// Footprint of one pixel on the rectangle's plane near its centre, along width and up [m].
Eigen::Vector2d PixelFootprint(const camera::Intrinsics& intrinsics, const PanelRectangle& rect);

}  // namespace depthbias::metrics
