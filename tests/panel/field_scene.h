#pragma once
// Field scenes rendered in memory, as a field looks rather than as a test bench: a camera 1.1 m
// high, pitched down and possibly rolled, over rough grass; the 1 × 1 m panel on a 6 cm post
// (coplanar with it, down to the grass), its bottom edge 0.55 m above the grass, turned a few
// degrees off the image plane; a bush, a person beside the panel, a hedge closing the scene.
// Textureless panels lose most of their pixels (holes independent per frame) while grass and
// vegetation keep theirs. Disparity noise, 1/32 px quantization, 1 mm depth counts.
// Truth: the panel's own footprint (pixels whose centre ray meets the panel before anything
// else), the median depth and hole rate of the panel's own samples over every frame.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "camera/intrinsics.h"
#include "records/depth_frame.h"

namespace depthbias::panel::test {

struct FieldSpec {
  std::string name = "field";
  double distance_m = 8.0;       // range of the panel centre
  double angle_deg = 0.0;        // horizontal azimuth of the panel centre, + right
  double camera_height_m = 1.1;
  double pitch_deg = 2.0;        // optical axis down
  double roll_deg = 0.0;
  double panel_yaw_deg = 2.0;    // turned off facing the camera horizontally
  double panel_bottom_m = 0.55;  // bottom edge above the grass
  double post_width_m = 0.06;
  double grass_roughness = 0.004;  // relative depth roughness of grass (static per pixel)
  double grass_height_m = 0.03;    // amplitude of the ground's undulation
  bool bush = true;                // 0.8 × 1.2 m, 6 m, 15° to the other side
  bool person = false;             // 0.5 × 0.3 × 1.75 m beside the panel, same distance
  bool hedge = true;               // at 40 m
  double panel_hole_rate = 0.97;   // per frame, on the panel
  double other_hole_rate = 0.2;    // grass, vegetation, person, post
  double noise_px = 0.08;          // disparity noise σ_d
  int frames = 10;
  std::uint64_t seed = 5;
};

class FieldScene {
 public:
  enum Surface : std::uint8_t { kNone, kGround, kPanel, kPost, kBush, kPerson, kHedge };

  camera::Intrinsics in = camera::D455::DepthIntrinsics();
  FieldSpec spec;
  Eigen::Matrix3d level_from_camera;
  Eigen::Vector3d panel_center_c, panel_normal_c;  // camera frame
  std::vector<float> depth_m;           // noise-free Z per pixel (0: nothing within range)
  std::vector<std::uint8_t> surface;    // what each pixel's centre ray meets first
  std::vector<records::DepthFrame> frames;
  double true_median_m = 0, true_hole_rate_pct = 0;
  double true_azimuth_deg = 0, true_tilt_deg = 0;

  explicit FieldScene(const FieldSpec& s) : spec(s) {
    constexpr double kDeg = M_PI / 180.0;
    level_from_camera = Eigen::AngleAxisd(-s.pitch_deg * kDeg, Eigen::Vector3d::UnitX()) *
                        Eigen::AngleAxisd(s.roll_deg * kDeg, Eigen::Vector3d::UnitZ());
    // Level frame: camera at the origin, y down, ground at y = camera height.
    const double h = s.camera_height_m;
    const double a = s.angle_deg * kDeg;
    const double center_y = h - s.panel_bottom_m - 0.5;  // panel centre height in level y
    const double horiz = std::sqrt(s.distance_m * s.distance_m - center_y * center_y);
    const Eigen::Vector3d pc(horiz * std::sin(a), center_y, horiz * std::cos(a));
    const double yaw = a + s.panel_yaw_deg * kDeg;
    const Eigen::Vector3d aw(std::cos(yaw), 0, -std::sin(yaw)), ah(0, -1, 0);
    quads_.push_back({kPanel, pc, aw, ah, 1.0, 1.0, 0.0});
    const double post_len = s.panel_bottom_m + 0.05;
    quads_.push_back({kPost, pc + Eigen::Vector3d(0, 0.5 + 0.5 * post_len, 0), aw, ah,
                      s.post_width_m, post_len, 0.0});
    if (s.person) {  // 1.0 m to the right of the panel's centre, facing the camera
      const Eigen::Vector3d c = pc + 1.0 * aw;
      const double cy = h - 0.875;
      AddBox(kPerson, {c.x(), cy, c.z()}, aw, 0.5, 0.3, 1.75, 0.01);
    }
    if (s.bush) {
      const double b = (a >= 0 ? -15.0 : 15.0) * kDeg;
      const Eigen::Vector3d c(6.0 * std::sin(b), h - 0.6, 6.0 * std::cos(b));
      AddBox(kBush, c, {std::cos(b), 0, -std::sin(b)}, 0.8, 0.8, 1.2, 0.04);
    }
    if (s.hedge)
      quads_.push_back({kHedge, {0, h - 1.5, 40.0}, {1, 0, 0}, {0, -1, 0}, 80.0, 3.0, 0.01});

    panel_center_c = level_from_camera.transpose() * pc;
    panel_normal_c = level_from_camera.transpose() * aw.cross(ah);
    true_azimuth_deg = std::atan2(panel_center_c.x(), panel_center_c.z()) / kDeg;
    true_tilt_deg = std::acos(std::fabs(panel_normal_c.z())) / kDeg;

    Render();
    MakeFrames();
  }

 private:
  struct Quad {
    Surface id;
    Eigen::Vector3d center, axis_w, axis_h;  // level frame
    double w, h;
    double roughness;  // relative static depth roughness
    // Parameter t of point = t·ray where the ray meets the rectangle; +inf if it misses.
    double Hit(const Eigen::Vector3d& ray) const {
      const Eigen::Vector3d n = axis_w.cross(axis_h);
      const double nr = n.dot(ray);
      if (std::fabs(nr) < 1e-12) return INFINITY;
      const double t = n.dot(center) / nr;
      if (!(t > 0)) return INFINITY;
      const Eigen::Vector3d q = t * ray - center;
      if (std::fabs(q.dot(axis_w)) > 0.5 * w || std::fabs(q.dot(axis_h)) > 0.5 * h)
        return INFINITY;
      return t;
    }
  };

  // A box standing with its front face toward the camera: front and two sides.
  void AddBox(Surface id, const Eigen::Vector3d& center, const Eigen::Vector3d& across,
              double width, double depth, double height, double roughness) {
    const Eigen::Vector3d up(0, -1, 0);
    const Eigen::Vector3d back = across.cross(up).normalized() * -1.0;  // away from the camera
    const Eigen::Vector3d fwd = back.z() > 0 ? back : -back;
    quads_.push_back({id, center - 0.5 * depth * fwd, across, up, width, height, roughness});
    quads_.push_back({id, center - 0.5 * width * across, fwd, up, depth, height, roughness});
    quads_.push_back({id, center + 0.5 * width * across, fwd, up, depth, height, roughness});
  }

  void Render() {
    const std::size_t n = static_cast<std::size_t>(in.width) * in.height;
    depth_m.assign(n, 0.f);
    surface.assign(n, kNone);
    std::mt19937_64 rng(spec.seed * 7919u + 17);
    std::normal_distribution<double> unit(0.0, 1.0);
    const double h = spec.camera_height_m, g = spec.grass_height_m;
    for (int v = 0; v < in.height; ++v) {
      for (int u = 0; u < in.width; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * in.width + u;
        const Eigen::Vector2d r2 = camera::PixelToNormalized(in, {u, v});
        const Eigen::Vector3d ray = level_from_camera * Eigen::Vector3d(r2.x(), r2.y(), 1.0);
        double t = INFINITY;
        Surface id = kNone;
        double rough = 0;
        if (ray.y() > 1e-9) {  // undulating grass: one fixed-point step on the height field
          const double t0 = h / ray.y();
          const double x = t0 * ray.x(), z = t0 * ray.z();
          const double dy = g * (std::sin(1.7 * x + 0.3) * std::sin(1.3 * z) +
                                 0.5 * std::sin(3.1 * x + 2.3 * z));
          t = (h + dy) / ray.y();
          id = kGround;
          rough = spec.grass_roughness;
        }
        for (const Quad& q : quads_) {
          const double tq = q.Hit(ray);
          if (tq < t) {
            t = tq;
            id = q.id;
            rough = q.roughness;
          }
        }
        const double e = unit(rng);  // static roughness draw, one per pixel
        if (id == kNone || !std::isfinite(t)) continue;
        const double z = t * (1.0 + rough * e);  // Z: the camera ray has z = 1
        if (z * std::sqrt(1 + r2.squaredNorm()) > 60.0) continue;
        depth_m[i] = static_cast<float>(z);
        surface[i] = id;
      }
    }
  }

  void MakeFrames() {
    const double fb = in.fx * camera::D455::kBaselineM;
    std::vector<std::uint16_t> panel_samples;
    std::size_t panel_slots = 0;
    for (int k = 0; k < spec.frames; ++k) {
      std::mt19937_64 rng(spec.seed * 1000003u + k);
      std::normal_distribution<double> noise(0.0, spec.noise_px);
      std::uniform_real_distribution<double> uni(0.0, 1.0);
      records::DepthFrame f;
      f.width = in.width;
      f.height = in.height;
      f.frame_number = static_cast<std::uint64_t>(k);
      f.timestamp_ms = 33.3 * k;
      f.counts.assign(depth_m.size(), 0);
      for (std::size_t i = 0; i < depth_m.size(); ++i) {
        if (surface[i] == kPanel) ++panel_slots;
        if (depth_m[i] <= 0) continue;
        const double holes = surface[i] == kPanel ? spec.panel_hole_rate : spec.other_hole_rate;
        if (uni(rng) < holes) continue;
        double d = fb / depth_m[i] + noise(rng);
        d = std::round(d * 32.0) / 32.0;
        if (d <= 0) continue;
        const double z = fb / d;
        if (z >= 65.0) continue;
        f.counts[i] = static_cast<std::uint16_t>(std::lround(z * 1000.0));
        if (surface[i] == kPanel) panel_samples.push_back(f.counts[i]);
      }
      frames.push_back(std::move(f));
    }
    std::sort(panel_samples.begin(), panel_samples.end());
    const std::size_t m = panel_samples.size();
    if (m > 0)
      true_median_m = 0.5e-3 * (panel_samples[(m - 1) / 2] + panel_samples[m / 2]);
    true_hole_rate_pct = 100.0 * (1.0 - static_cast<double>(m) / std::max<std::size_t>(1, panel_slots));
  }

  std::vector<Quad> quads_;
};

}  // namespace depthbias::panel::test
