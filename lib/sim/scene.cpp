#include "sim/scene.h"

#include "camera/presets.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

#include <Eigen/Geometry>

namespace depthbias::sim {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

bool Fail(std::string* why, const std::string& message) {
  if (why) *why = message;
  return false;
}

std::string Number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Horizontal distance of the panel centre from the camera for a nominal distance meant as
// range or as depth.
double HorizontalDistance(const SceneParams& scene, const Eigen::Matrix3d& level_from_camera,
                          DistanceIs meaning, double distance_m, double angle_rad) {
  const double drop_m = scene.camera_height_m - scene.panel_center_height_m;  // + below
  if (meaning == DistanceIs::kRange) {
    // |(h sinα, drop, h cosα)| = D.
    return std::sqrt(std::max(distance_m * distance_m - drop_m * drop_m, 0.0));
  }
  // Depth: the camera-frame z of p = (h sinα, drop, h cosα) equals D, with
  // z_camera = r·p where r is the camera's optical axis in the level frame.
  const Eigen::Vector3d axis = level_from_camera.col(2);
  const double per_h = axis.x() * std::sin(angle_rad) + axis.z() * std::cos(angle_rad);
  return (distance_m - axis.y() * drop_m) / per_h;
}

// Bit for bit: NaN equals itself, 0 and −0 differ (a cast may divide by either).
bool Same(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool Same(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return Same(a.x(), b.x()) && Same(a.y(), b.y()) && Same(a.z(), b.z());
}

}  // namespace

bool Identical(const SceneParams& a, const SceneParams& b) {
  if (!(Same(a.camera_height_m, b.camera_height_m) &&
        Same(a.camera_pitch_deg, b.camera_pitch_deg) &&
        Same(a.camera_roll_deg, b.camera_roll_deg) && Same(a.ground_texture, b.ground_texture) &&
        Same(a.panel_width_m, b.panel_width_m) && Same(a.panel_height_m, b.panel_height_m) &&
        Same(a.panel_center_height_m, b.panel_center_height_m) &&
        Same(a.panel_yaw_deg, b.panel_yaw_deg) && Same(a.panel_texture, b.panel_texture) &&
        Same(a.background_distance_m, b.background_distance_m) &&
        Same(a.background_texture, b.background_texture) && a.panel == b.panel &&
        Same(a.hedge.distance_m, b.hedge.distance_m) && Same(a.hedge.height_m, b.hedge.height_m) &&
        Same(a.hedge.texture, b.hedge.texture) && a.obstacles.size() == b.obstacles.size()))
    return false;
  for (size_t i = 0; i < a.obstacles.size(); ++i) {
    const Obstacle &p = a.obstacles[i], &q = b.obstacles[i];
    if (!(p.kind == q.kind && p.shape == q.shape && Same(p.range_m, q.range_m) &&
          Same(p.azimuth_deg, q.azimuth_deg) && Same(p.width_m, q.width_m) &&
          Same(p.depth_m, q.depth_m) && Same(p.height_m, q.height_m) &&
          Same(p.texture, q.texture)))
      return false;
  }
  return true;
}

bool Identical(const PanelPose& a, const PanelPose& b) {
  return Same(a.center_m, b.center_m) && Same(a.normal, b.normal) &&
         Same(a.axis_width, b.axis_width) && Same(a.axis_height, b.axis_height) &&
         Same(a.width_m, b.width_m) && Same(a.height_m, b.height_m);
}

std::string DistanceIsName(DistanceIs d) { return d == DistanceIs::kRange ? "range" : "depth"; }

bool ParseDistanceIs(const std::string& name, DistanceIs* d) {
  if (name == "range") {
    *d = DistanceIs::kRange;
  } else if (name == "depth") {
    *d = DistanceIs::kDepth;
  } else {
    return false;
  }
  return true;
}

bool ObstacleOfKind(const std::string& kind, Obstacle* o) {
  Obstacle d;
  d.kind = kind;
  if (kind == "person" || kind == "box") {
    d.shape = ObstacleShape::kBox;  // the defaults: 0.5 × 0.3 × 1.75 m, texture 0.5
  } else if (kind == "bush" || kind == "ellipsoid") {
    d.shape = ObstacleShape::kEllipsoid;
    d.width_m = 1.0;
    d.depth_m = 0.8;
    d.height_m = 0.9;
    d.texture = 0.7;
  } else {
    return false;
  }
  *o = d;
  return true;
}

bool Obstacle::IsValid(std::string* why) const {
  if (!(width_m > 0) || !(depth_m > 0) || !(height_m > 0) || !std::isfinite(width_m) ||
      !std::isfinite(depth_m) || !std::isfinite(height_m))
    return Fail(why, "obstacle '" + kind + "': width_m, depth_m and height_m must be > 0");
  if (!(range_m > 0) || !std::isfinite(range_m))
    return Fail(why, "obstacle '" + kind + "': range_m must be > 0");
  if (!(std::fabs(azimuth_deg) < 80))
    return Fail(why, "obstacle '" + kind + "': azimuth_deg must be in (-80, 80)");
  if (!(texture >= 0 && texture <= 1))
    return Fail(why, "obstacle '" + kind + "': texture must be in [0, 1]");
  return true;
}

bool SceneParams::IsValid(std::string* why) const {
  if (!(camera_height_m > 0)) return Fail(why, "camera_height_m must be > 0");
  if (!(std::fabs(camera_pitch_deg) < 80))
    return Fail(why, "camera_pitch_deg must be in (-80, 80)");
  if (!(std::fabs(camera_roll_deg) < 80)) return Fail(why, "camera_roll_deg must be in (-80, 80)");
  if (!(panel_width_m > 0) || !(panel_height_m > 0))
    return Fail(why, "panel_width_m and panel_height_m must be > 0");
  if (!(panel_center_height_m >= 0)) return Fail(why, "panel_center_height_m must be >= 0");
  if (!(std::fabs(panel_yaw_deg) < 89)) return Fail(why, "panel_yaw_deg must be in (-89, 89)");
  if (!(background_distance_m > 0)) return Fail(why, "background_distance_m must be > 0");
  for (double t : {ground_texture, panel_texture, background_texture, hedge.texture})
    if (!(t >= 0 && t <= 1)) return Fail(why, "textures must be in [0, 1]");
  for (const Obstacle& o : obstacles) {
    if (!o.IsValid(why)) return false;
    // The face's centre is half the height above the ground: the range must reach it.
    if (!(o.range_m > std::fabs(camera_height_m - 0.5 * o.height_m)))
      return Fail(why, "obstacle '" + o.kind + "' at " + Number(o.range_m) +
                           " m: range_m must exceed the face centre's drop below the camera");
  }
  if (!(hedge.distance_m >= 0) || !std::isfinite(hedge.distance_m))
    return Fail(why, "hedge.distance_m must be >= 0 (0: no hedge)");
  if (hedge.distance_m > 0 && !(hedge.height_m > 0))
    return Fail(why, "hedge.height_m must be > 0");
  if (!panel && obstacles.empty() && hedge.distance_m == 0)
    return Fail(why, "a scene without a panel needs obstacles or a hedge");
  return true;
}

bool ProtocolParams::IsValid(std::string* why) const {
  if (distances_m.empty() || angles_deg.empty() || presets.empty() || emitters.empty() ||
      lights.empty())
    return Fail(why, "distances_m, angles_deg, presets, emitters and lights must not be empty");
  for (double d : distances_m)
    if (!(d > 0) || !std::isfinite(d)) return Fail(why, "distances_m must be > 0");
  for (double a : angles_deg)
    if (!(std::fabs(a) < 60)) return Fail(why, "angles_deg must be in (-60, 60)");
  for (const auto& p : presets) {
    double v;
    if (!camera::PresetOptionValue(p, &v) || (v != 3 && v != 4))
      return Fail(why, "unknown preset '" + p + "' (HA or HD)");
  }
  if (frames < 1) return Fail(why, "frames must be >= 1");
  if (!(fps > 0)) return Fail(why, "fps must be > 0");
  return scene.IsValid(why);
}

std::string CellName(const Cell& c) {
  const std::string where =
      c.panel ? Number(c.distance_m) + "m_" + Number(c.angle_deg) + "deg_" : "obstacles_";
  return "sim_" + c.light + "_emitter-" + (c.emitter_on ? "on" : "off") + "_" + where + c.preset;
}

std::vector<Cell> MakeCells(const ProtocolParams& p) {
  std::vector<Cell> cells;
  // Without a panel the test points place nothing: one recording per (light, emitter, preset).
  const std::vector<double> angles =
      p.scene.panel ? p.angles_deg : std::vector<double>{p.angles_deg.front()};
  const std::vector<double> distances =
      p.scene.panel ? p.distances_m : std::vector<double>{p.distances_m.front()};
  for (const auto& light : p.lights)
    for (bool emitter : p.emitters)
      for (double angle : angles)
        for (const auto& preset : p.presets)
          for (double distance : distances) {
            Cell c;
            c.panel = p.scene.panel;
            c.distance_m = distance;
            c.angle_deg = angle;
            c.preset = preset;
            c.emitter_on = emitter;
            c.light = light;
            c.name = CellName(c);
            cells.push_back(c);
          }
  return cells;
}

Eigen::Matrix3d LevelFromCamera(const SceneParams& scene) {
  // Pitch down by p: the optical axis becomes (0, sin p, cos p) in the level frame, a rotation
  // about x by −p; roll about the optical axis comes first.
  return (Eigen::AngleAxisd(-scene.camera_pitch_deg * kDegToRad, Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(scene.camera_roll_deg * kDegToRad, Eigen::Vector3d::UnitZ()))
      .toRotationMatrix();
}

PanelPose PlacePanel(const SceneParams& scene, DistanceIs distance_is, const Cell& cell,
                     double range_vs_depth_weight, double extra_yaw_deg) {
  const Eigen::Matrix3d r = LevelFromCamera(scene);
  const double a = cell.angle_deg * kDegToRad;
  const DistanceIs other = distance_is == DistanceIs::kRange ? DistanceIs::kDepth
                                                             : DistanceIs::kRange;
  const double h_nominal = HorizontalDistance(scene, r, distance_is, cell.distance_m, a);
  const double h_other = HorizontalDistance(scene, r, other, cell.distance_m, a);
  const double h = h_nominal + range_vs_depth_weight * (h_other - h_nominal);
  const double drop_m = scene.camera_height_m - scene.panel_center_height_m;
  const Eigen::Vector3d center_level(h * std::sin(a), drop_m, h * std::cos(a));

  // The panel stands vertical, facing back along the camera's horizontal viewing direction
  // (parallel to the image plane when pitch and roll are 0), then turned by its yaw.
  Eigen::Vector3d forward = r.col(2);
  forward.y() = 0;
  forward.normalize();
  const double yaw = (scene.panel_yaw_deg + extra_yaw_deg) * kDegToRad;
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Vector3d normal_level = turn * (-forward);
  const Eigen::Vector3d width_level = turn * Eigen::Vector3d(forward.z(), 0, -forward.x());

  PanelPose pose;
  const Eigen::Matrix3d camera_from_level = r.transpose();
  pose.center_m = camera_from_level * center_level;
  pose.normal = camera_from_level * normal_level;
  pose.axis_width = camera_from_level * width_level;
  pose.axis_height = camera_from_level * Eigen::Vector3d::UnitY();
  pose.width_m = scene.panel_width_m;
  pose.height_m = scene.panel_height_m;
  return pose;
}

std::vector<ObstaclePose> PlaceObstacles(const SceneParams& scene) {
  const Eigen::Matrix3d camera_from_level = LevelFromCamera(scene).transpose();
  std::vector<ObstaclePose> poses;
  for (const Obstacle& o : scene.obstacles) {
    // The face centre F = (h sinφ, drop, h cosφ) in the level frame, |F| = range; the obstacle
    // extends away from the camera along the horizontal line of sight.
    const double a = o.azimuth_deg * kDegToRad;
    const double drop_m = scene.camera_height_m - 0.5 * o.height_m;  // + below the camera
    const double h = std::sqrt(std::max(o.range_m * o.range_m - drop_m * drop_m, 0.0));
    const Eigen::Vector3d away(std::sin(a), 0, std::cos(a));
    const Eigen::Vector3d across(std::cos(a), 0, -std::sin(a));
    const Eigen::Vector3d face_level(h * std::sin(a), drop_m, h * std::cos(a));
    ObstaclePose pose;
    pose.obstacle = o;
    pose.face_center_m = camera_from_level * face_level;
    pose.center_m = camera_from_level * (face_level + 0.5 * o.depth_m * away);
    pose.axes.col(0) = camera_from_level * across;
    pose.axes.col(1) = camera_from_level * Eigen::Vector3d::UnitY();
    pose.axes.col(2) = camera_from_level * away;
    pose.half_m = 0.5 * Eigen::Vector3d(o.width_m, o.height_m, o.depth_m);
    pose.face_range_m = pose.face_center_m.norm();
    pose.face_azimuth_deg = std::atan2(pose.face_center_m.x(), pose.face_center_m.z()) / kDegToRad;
    poses.push_back(pose);
  }
  return poses;
}

RayCaster::RayCaster(const SceneParams& scene, const PanelPose& panel)
    : scene_(scene),
      panel_(panel),
      level_from_camera_(LevelFromCamera(scene)),
      obstacles_(PlaceObstacles(scene)) {
  panel_offset_ = panel_.normal.dot(panel_.center_m);
}

namespace {

// Depth Z (the ray parameter of p = t·(xn, yn, 1)) where the ray enters an obstacle; 0 if it
// misses. In the obstacle's frame the ray starts at o = Aᵀ(0 − c) with direction Aᵀ·ray.
double HitObstacle(const ObstaclePose& pose, double xn, double yn) {
  const Eigen::Vector3d ray(xn, yn, 1.0);
  const Eigen::Vector3d o = -(pose.axes.transpose() * pose.center_m);
  const Eigen::Vector3d d = pose.axes.transpose() * ray;
  if (pose.obstacle.shape == ObstacleShape::kEllipsoid) {
    // |(o + t·d) / half|² = 1: the nearer root.
    const Eigen::Vector3d os = o.cwiseQuotient(pose.half_m), ds = d.cwiseQuotient(pose.half_m);
    const double qa = ds.squaredNorm(), qb = os.dot(ds), qc = os.squaredNorm() - 1.0;
    const double disc = qb * qb - qa * qc;
    if (disc < 0 || qa <= 0) return 0.0;
    const double t = (-qb - std::sqrt(disc)) / qa;
    return t > 0 ? t : 0.0;
  }
  // Box: slabs.
  double t_in = 0.0, t_out = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (std::fabs(d[k]) < 1e-15) {
      if (std::fabs(o[k]) > pose.half_m[k]) return 0.0;
      continue;
    }
    double t0 = (-pose.half_m[k] - o[k]) / d[k], t1 = (pose.half_m[k] - o[k]) / d[k];
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
    if (t_in > t_out) return 0.0;
  }
  return t_in > 0 ? t_in : 0.0;
}

}  // namespace

Hit RayCaster::Cast(double xn, double yn) const {
  // The ray p(t) = t·(xn, yn, 1) in the camera frame: t is the depth Z of the point. Plain
  // scalars: this runs once per pixel and recording.
  const Eigen::Vector3d& n = panel_.normal;
  const Eigen::Vector3d& c = panel_.center_m;
  const Eigen::Vector3d& aw = panel_.axis_width;
  const Eigen::Vector3d& ah = panel_.axis_height;
  const Eigen::Matrix3d& r = level_from_camera_;
  Hit best;
  auto take = [&](double t, Surface s, double texture) {
    if (t > 0 && std::isfinite(t) && (best.surface == Surface::kNone || t < best.depth_m)) {
      best.depth_m = t;
      best.surface = s;
      best.texture = texture;
    }
  };
  // Panel: n·(t·ray) = n·c, inside the rectangle.
  const double denom = n.x() * xn + n.y() * yn + n.z();
  if (scene_.panel && std::fabs(denom) > 1e-12) {
    const double t = panel_offset_ / denom;
    const double qx = t * xn - c.x(), qy = t * yn - c.y(), qz = t - c.z();
    if (std::fabs(qx * aw.x() + qy * aw.y() + qz * aw.z()) <= 0.5 * panel_.width_m &&
        std::fabs(qx * ah.x() + qy * ah.y() + qz * ah.z()) <= 0.5 * panel_.height_m)
      take(t, Surface::kPanel, scene_.panel_texture);
  }
  // The ray in the level frame: ground at y_level = camera height, wall at z_level = distance.
  const double ly = r(1, 0) * xn + r(1, 1) * yn + r(1, 2);
  const double lz = r(2, 0) * xn + r(2, 1) * yn + r(2, 2);
  if (ly > 1e-12) take(scene_.camera_height_m / ly, Surface::kGround, scene_.ground_texture);
  if (lz > 1e-12)
    take(scene_.background_distance_m / lz, Surface::kBackground, scene_.background_texture);
  // Hedge: the wall z_level = its distance, from the ground (y_level = camera height) up to its
  // height.
  if (scene_.hedge.distance_m > 0 && lz > 1e-12) {
    const double t = scene_.hedge.distance_m / lz;
    if (t * ly >= scene_.camera_height_m - scene_.hedge.height_m)
      take(t, Surface::kHedge, scene_.hedge.texture);
  }
  for (const ObstaclePose& pose : obstacles_)
    take(HitObstacle(pose, xn, yn), Surface::kObstacle, pose.obstacle.texture);
  return best;
}

}  // namespace depthbias::sim
