#pragma once
// The scene of one recording: a camera above a textured ground, the 1×1 m grey panel at a test
// point, and a background wall; optionally obstacles standing on the ground (person-sized boxes,
// bushes) and a far hedge; the article's protocol that lists the test points; and the ray caster
// that gives the true depth Z of every pixel.
//
// Frames: the camera frame is librealsense's (x right, y down, z forward). The level frame has
// its origin at the camera's optical centre, y down along gravity and z forward horizontally; the
// camera is pitched (optical axis down for pitch_deg > 0) and rolled (about its optical axis)
// with respect to it. The ground is the plane y_level = camera_height_m.

#include <string>
#include <vector>

#include <Eigen/Core>

namespace depthbias::sim {

// How a protocol's nominal distance is meant (DESIGN.md: Z = range·cos α).
enum class DistanceIs { kRange, kDepth };
std::string DistanceIsName(DistanceIs d);
bool ParseDistanceIs(const std::string& name, DistanceIs* d);

// Something standing on the ground in front of the camera. Its position is given as a detector
// reports it: the range from the optical centre to the centre of its face towards the camera,
// and the horizontal azimuth of that point (+ right). It is turned to face the camera.
enum class ObstacleShape { kBox, kEllipsoid };
struct Obstacle {
  std::string kind = "person";  // person (a box), bush (an ellipsoid), box, ellipsoid
  ObstacleShape shape = ObstacleShape::kBox;
  double range_m = 5.0;        // to the centre of the face towards the camera [m]
  double azimuth_deg = 0.0;    // horizontal, + to the right [deg]
  double width_m = 0.5;        // across the line of sight [m]
  double depth_m = 0.3;        // along the line of sight [m]
  double height_m = 1.75;      // above the ground [m]
  double texture = 0.5;        // [0, 1] (clothes; foliage 0.7)

  bool IsValid(std::string* why) const;
};
// Defaults of a kind: person 0.5 × 0.3 × 1.75 m box (texture 0.5), bush 1.0 × 0.8 × 0.9 m
// ellipsoid (texture 0.7). False for an unknown kind.
bool ObstacleOfKind(const std::string& kind, Obstacle* obstacle);

// A hedge across the whole view: a vertical wall of foliage from the ground up.
struct Hedge {
  double distance_m = 0.0;  // forward horizontal distance of its face [m]; 0: no hedge
  double height_m = 2.0;    // [m]
  double texture = 0.7;     // [0, 1]
};

struct SceneParams {
  double camera_height_m = 1.0;      // optical centre above the ground [m]
  double camera_pitch_deg = 0.0;     // optical axis below the horizon [deg]
  double camera_roll_deg = 0.0;      // about the optical axis, + clockwise seen from behind [deg]
  double ground_texture = 0.8;       // texture measure of the ground (grass) in [0, 1]
  double panel_width_m = 1.0;        // [m]
  double panel_height_m = 1.0;       // [m]
  double panel_center_height_m = 1.0;  // panel centre above the ground [m]
  double panel_yaw_deg = 0.0;        // turn of the panel about the vertical; 0 = facing the camera
  double panel_texture = 0.2;        // texture measure of the grey panel in [0, 1]
  double background_distance_m = 50.0;  // vertical wall at this forward distance [m]
  double background_texture = 0.5;      // [0, 1]
  bool panel = true;  // false: no panel (an obstacle scene; the cell's distance places nothing)
  std::vector<Obstacle> obstacles;
  Hedge hedge;

  bool IsValid(std::string* why) const;
};
// Every field bit for bit (a field added to SceneParams, Obstacle or Hedge must be compared
// here: StereoSim's cache of ray casts is keyed by it).
bool Identical(const SceneParams& a, const SceneParams& b);

// One recording of a protocol.
struct Cell {
  bool panel = true;      // false: an obstacle scene (named ..._obstacles_<preset>)
  std::string name;       // recording id, also the bag's file stem
  double distance_m = 4;  // nominal distance
  double angle_deg = 0;   // nominal horizontal off-axis position, + to the right
  std::string preset = "HA";
  bool emitter_on = false;
  std::string light = "daylight";
};

struct ProtocolParams {
  std::vector<double> distances_m{4, 8, 12, 16};
  std::vector<double> angles_deg{0, 10, 20, 35};
  std::vector<std::string> presets{"HA", "HD"};
  std::vector<bool> emitters{false, true};
  std::vector<std::string> lights{"daylight", "sunset"};
  DistanceIs distance_is = DistanceIs::kRange;
  int frames = 30;    // frames per recording
  double fps = 30.0;  // [frames/s]
  SceneParams scene;

  bool IsValid(std::string* why) const;
};

// The recordings of a protocol, in the article's order (light, emitter, angle, preset,
// distance), named like the article's ids: sim_<light>_emitter-<on|off>_<D>m_<A>deg_<preset>;
// without a panel, one recording per (light, emitter, preset):
// sim_<light>_emitter-<on|off>_obstacles_<preset>.
std::vector<Cell> MakeCells(const ProtocolParams& protocol);
std::string CellName(const Cell& cell);


// Where the panel stands, in the camera frame.
struct PanelPose {
  Eigen::Vector3d center_m = Eigen::Vector3d(0, 0, 4);  // camera frame [m]
  Eigen::Vector3d normal = Eigen::Vector3d(0, 0, -1);   // unit, towards the camera side
  Eigen::Vector3d axis_width = Eigen::Vector3d(1, 0, 0);   // unit, along the panel's width
  Eigen::Vector3d axis_height = Eigen::Vector3d(0, 1, 0);  // unit, along its height (down)
  double width_m = 1.0;
  double height_m = 1.0;
};
bool Identical(const PanelPose& a, const PanelPose& b);  // bit for bit

// Camera orientation: R such that v_level = R · v_camera.
Eigen::Matrix3d LevelFromCamera(const SceneParams& scene);

// Places the panel of a cell. range_vs_depth_weight in [0, 1] moves it from the protocol's
// meaning of the nominal distance towards the other meaning (the range_vs_depth effect);
// extra_yaw_deg turns it further (the panel_tilt effect).
PanelPose PlacePanel(const SceneParams& scene, DistanceIs distance_is, const Cell& cell,
                     double range_vs_depth_weight = 0.0, double extra_yaw_deg = 0.0);

// Where an obstacle stands, in the camera frame: a box or an ellipsoid with its centre, its axes
// (unit: across, down, along the line of sight away from the camera) and half extents.
struct ObstaclePose {
  Obstacle obstacle;
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // columns: across, down, away
  Eigen::Vector3d half_m = Eigen::Vector3d::Zero();    // half width, height, depth
  Eigen::Vector3d face_center_m = Eigen::Vector3d::Zero();  // the truth a detector reports
  double face_range_m = 0.0;
  double face_azimuth_deg = 0.0;  // atan2(x, z) of the face centre in the camera frame
};
std::vector<ObstaclePose> PlaceObstacles(const SceneParams& scene);

// What a ray from the optical centre meets first.
enum class Surface : unsigned char {
  kNone = 0, kPanel = 1, kGround = 2, kBackground = 3, kObstacle = 4, kHedge = 5
};
struct Hit {
  double depth_m = 0.0;  // Z of the hit point in the camera frame; 0 when nothing is hit
  Surface surface = Surface::kNone;
  double texture = 0.0;
};

// Casts the ray through normalized image coordinates (x/z, y/z) of the camera frame.
class RayCaster {
 public:
  RayCaster(const SceneParams& scene, const PanelPose& panel);
  Hit Cast(double x_normalized, double y_normalized) const;

 private:
  SceneParams scene_;
  PanelPose panel_;
  Eigen::Matrix3d level_from_camera_;
  double panel_offset_ = 0.0;  // normal · center
  std::vector<ObstaclePose> obstacles_;
};

}  // namespace depthbias::sim
