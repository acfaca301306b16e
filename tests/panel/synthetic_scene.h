#pragma once
// Test scenes rendered in memory: a level camera above a ground plane, a 1×1 m panel facing
// the camera and optional clutter, with disparity noise, 1/32 px quantization and random holes
// on the panel. Truth (footprint, depths) comes from the same ray casting without noise.

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "records/depth_frame.h"
#include "camera/intrinsics.h"

namespace depthbias::panel::test {

struct Quad {  // rectangle: centre, unit axes, size
  Eigen::Vector3d center, axis_w, axis_h;
  double w, h;
  // Z where the ray (x/z, y/z, 1) meets the rectangle, or +inf.
  double Hit(const Eigen::Vector3d& ray) const {
    const Eigen::Vector3d n = axis_w.cross(axis_h);
    const double nr = n.dot(ray);
    if (std::fabs(nr) < 1e-12) return INFINITY;
    const double z = n.dot(center) / nr;
    if (!(z > 0)) return INFINITY;
    const Eigen::Vector3d q = z * ray - center;
    if (std::fabs(q.dot(axis_w)) > 0.5 * w || std::fabs(q.dot(axis_h)) > 0.5 * h) return INFINITY;
    return z;
  }
};

struct SceneSpec {
  double distance_m = 8.0;     // range of the panel centre
  double angle_deg = 0.0;      // horizontal off-axis angle, + right
  double camera_height_m = 1.3;
  double panel_center_height_m = 1.0;
  double panel_size_m = 1.0;
  double yaw_extra_deg = 0.0;  // panel turned away from facing the camera
  double hole_rate = 0.05;     // share of the panel's pixels without depth in each frame
  double noise_px = 0.05;      // disparity noise σ_d
  bool clutter = false;        // a bigger plane and a small box
  int frames = 10;
  std::uint64_t seed = 3;
};

struct Scene {
  camera::Intrinsics in = camera::D455::DepthIntrinsics();
  SceneSpec spec;
  Quad panel;
  std::vector<Quad> others;  // clutter faces
  std::vector<double> truth_depth;  // noise-free Z per pixel, 0 where nothing is hit
  std::vector<char> footprint;      // pixel centre ray meets the panel first

  explicit Scene(const SceneSpec& s) : spec(s) {
    const double a = s.angle_deg * M_PI / 180;
    const double dy = s.camera_height_m - s.panel_center_height_m;  // camera y points down
    const double horiz = std::sqrt(s.distance_m * s.distance_m - dy * dy);
    panel.center = {horiz * std::sin(a), dy, horiz * std::cos(a)};
    const double yaw = a + s.yaw_extra_deg * M_PI / 180;
    panel.axis_w = {std::cos(yaw), 0, -std::sin(yaw)};  // normal faces the camera horizontally
    panel.axis_h = {0, -1, 0};
    panel.w = panel.h = s.panel_size_m;
    if (s.clutter) {
      // A 3 × 2 m wall to the other side and farther, and a 0.4 m box on the ground nearer.
      const double b = -a - 20 * M_PI / 180;
      const double r = s.distance_m + 4;
      others.push_back({{r * std::sin(b), s.camera_height_m - 1.0, r * std::cos(b)},
                        {std::cos(b), 0, -std::sin(b)}, {0, -1, 0}, 3.0, 2.0});
      const double c = a + (a >= 0 ? -12 : 12) * M_PI / 180;
      const double rb = 0.6 * s.distance_m;
      const Eigen::Vector3d bc(rb * std::sin(c), s.camera_height_m - 0.2, rb * std::cos(c));
      const Eigen::Vector3d ex(std::cos(c), 0, -std::sin(c)), ez(std::sin(c), 0, std::cos(c));
      others.push_back({bc - 0.2 * ez, ex, {0, -1, 0}, 0.4, 0.4});
      others.push_back({bc - 0.2 * ex, ez, {0, -1, 0}, 0.4, 0.4});
      others.push_back({bc + 0.2 * ex, ez, {0, -1, 0}, 0.4, 0.4});
      others.push_back({bc - Eigen::Vector3d(0, 0.2, 0), ex, ez, 0.4, 0.4});
    }
    const std::size_t n = static_cast<std::size_t>(in.width) * in.height;
    truth_depth.assign(n, 0.0);
    footprint.assign(n, 0);
    for (int v = 0; v < in.height; ++v) {
      for (int u = 0; u < in.width; ++u) {
        const Eigen::Vector2d r2 = camera::PixelToNormalized(in, {u, v});
        const Eigen::Vector3d ray(r2.x(), r2.y(), 1);
        double z = INFINITY;
        if (ray.y() > 1e-9) z = s.camera_height_m / ray.y();  // ground y = camera height
        for (const Quad& q : others) z = std::min(z, q.Hit(ray));
        const double zp = panel.Hit(ray);
        const std::size_t i = static_cast<std::size_t>(v) * in.width + u;
        if (std::isfinite(zp) && zp <= z) {
          z = zp;
          footprint[i] = 1;
        }
        if (z * ray.norm() < 60.0) truth_depth[i] = z;
      }
    }
  }

  // Frame k: disparity f·B/Z plus Gaussian noise, quantized to 1/32 px, back to 1 mm counts.
  records::DepthFrame Frame(int k) const {
    std::mt19937_64 rng(spec.seed * 1000003u + k);
    std::normal_distribution<double> noise(0.0, spec.noise_px);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    records::DepthFrame f;
    f.width = in.width;
    f.height = in.height;
    f.frame_number = k;
    f.counts.assign(truth_depth.size(), 0);
    const double fb = in.fx * camera::D455::kBaselineM;
    for (std::size_t i = 0; i < truth_depth.size(); ++i) {
      if (truth_depth[i] <= 0) continue;
      if (footprint[i] && uni(rng) < spec.hole_rate) continue;
      double d = fb / truth_depth[i] + noise(rng);
      d = std::round(d * 32.0) / 32.0;
      if (d <= 0) continue;
      const double z = fb / d;
      if (z < 65.0) f.counts[i] = static_cast<std::uint16_t>(std::lround(z * 1000.0));
    }
    return f;
  }

  double TrueMedianDepth() const {
    std::vector<double> z;
    for (std::size_t i = 0; i < footprint.size(); ++i)
      if (footprint[i]) z.push_back(truth_depth[i]);
    std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
    return z[z.size() / 2];
  }
};

}  // namespace depthbias::panel::test
