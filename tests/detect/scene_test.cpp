// The simulator's obstacle scenes: people and bushes stand on the ground where the protocol puts
// them (range and azimuth of the face towards the camera), a hedge far behind, scenes without a
// panel, and their YAML.
#include <gtest/gtest.h>

#include <cmath>

#include "sim/config_yaml.h"
#include "sim/scene.h"
#include "sim/stereo_sim.h"

namespace depthbias::sim {
namespace {

SceneParams WithObstacles(double pitch_deg = 0.0) {
  SceneParams s;
  s.panel = false;
  s.camera_pitch_deg = pitch_deg;
  Obstacle person, bush;
  ObstacleOfKind("person", &person);
  person.range_m = 8.0;
  person.azimuth_deg = -20.0;
  ObstacleOfKind("bush", &bush);
  bush.range_m = 5.0;
  bush.azimuth_deg = 15.0;
  s.obstacles = {person, bush};
  s.hedge.distance_m = 22.0;
  return s;
}

TEST(ObstacleScene, FacesStandWhereTheProtocolSays) {
  for (double pitch : {0.0, 6.0}) {
    const SceneParams s = WithObstacles(pitch);
    const auto poses = PlaceObstacles(s);
    ASSERT_EQ(poses.size(), 2u);
    EXPECT_NEAR(poses[0].face_range_m, 8.0, 1e-9);
    EXPECT_NEAR(poses[1].face_range_m, 5.0, 1e-9);
    // Azimuth of the face's centre in the camera frame: the level azimuth when not pitched.
    if (pitch == 0.0) {
      EXPECT_NEAR(poses[0].face_azimuth_deg, -20.0, 1e-9);
    }
    // Standing on the ground: the bottom at the ground's height, facing the camera.
    const Eigen::Matrix3d level_from_camera = LevelFromCamera(s);
    const Eigen::Vector3d bottom =
        level_from_camera * (poses[0].center_m + poses[0].half_m.y() * poses[0].axes.col(1));
    EXPECT_NEAR(bottom.y(), s.camera_height_m, 1e-9);
    const Eigen::Vector3d towards = -(level_from_camera * poses[0].axes.col(2));
    const Eigen::Vector3d face = level_from_camera * poses[0].face_center_m;
    EXPECT_NEAR(towards.dot(-Eigen::Vector3d(face.x(), 0, face.z()).normalized()), 1.0, 1e-9);
  }
}

TEST(ObstacleScene, RaysHitFacesBushesHedgeAndNoPanel) {
  const SceneParams s = WithObstacles();
  const auto poses = PlaceObstacles(s);
  const RayCaster caster(s, PanelPose{});  // the default panel at 4 m ahead is switched off
  const Eigen::Vector3d face = poses[0].face_center_m;
  const Hit person = caster.Cast(face.x() / face.z(), face.y() / face.z());
  EXPECT_EQ(person.surface, Surface::kObstacle);
  EXPECT_NEAR(person.depth_m, face.z(), 1e-9);
  const Eigen::Vector3d bush = poses[1].face_center_m;
  const Hit b = caster.Cast(bush.x() / bush.z(), bush.y() / bush.z());
  EXPECT_EQ(b.surface, Surface::kObstacle);
  EXPECT_NEAR(b.depth_m, bush.z(), 1e-6);  // the ellipsoid's nearest point on that ray
  const Hit ahead = caster.Cast(0.0, -0.02);  // just above the horizon, straight ahead
  EXPECT_EQ(ahead.surface, Surface::kHedge);
  EXPECT_NEAR(ahead.depth_m, 22.0, 1e-9);
  EXPECT_EQ(caster.Cast(0.0, -0.3).surface, Surface::kBackground);  // over the hedge
  SceneParams with_panel = s;
  with_panel.panel = true;
  EXPECT_EQ(RayCaster(with_panel, PanelPose{}).Cast(0.0, 0.0).surface, Surface::kPanel);
}

TEST(ObstacleScene, ProtocolYamlWithoutPanelGivesOneRecordingPerScenario) {
  ProtocolParams p;
  std::string sensor, why;
  ASSERT_TRUE(ParseProtocolYaml(R"(protocol: {presets: [HA, HD], emitters: ["on"]}
scene:
  panel: off
  obstacles:
    - {kind: person, range_m: 6, azimuth_deg: 10}
    - {kind: bush, range_m: 9, azimuth_deg: -12, height_m: 1.2}
    - {kind: box, range_m: 3, azimuth_deg: 0, width_m: 1, depth_m: 1, height_m: 0.5}
  hedge: {distance_m: 25, height_m: 2.5}
)",
                                &p, &sensor, &why))
      << why;
  ASSERT_EQ(p.scene.obstacles.size(), 3u);
  EXPECT_EQ(p.scene.obstacles[0].height_m, 1.75);  // a person's default
  EXPECT_EQ(p.scene.obstacles[1].shape, ObstacleShape::kEllipsoid);
  EXPECT_EQ(p.scene.obstacles[1].height_m, 1.2);
  EXPECT_EQ(p.scene.hedge.height_m, 2.5);
  const auto cells = MakeCells(p);
  ASSERT_EQ(cells.size(), 4u);  // 2 lights × 1 emitter × 2 presets
  EXPECT_EQ(cells[0].name, "sim_daylight_emitter-on_obstacles_HA");
}

TEST(ObstacleScene, BadObstaclesAreRefusedNamingThem) {
  struct Case {
    std::string yaml, says;
  };
  for (const Case& c : std::vector<Case>{
           {"scene: {obstacles: [{kind: tree, range_m: 5, azimuth_deg: 0}]}\n", "unknown kind"},
           {"scene: {obstacles: [{kind: person, azimuth_deg: 0}]}\n", "range_m"},
           {"scene: {obstacles: [{kind: person, range_m: 5, azimuth_deg: 0, size: 2}]}\n",
            "unknown key 'size'"},
           {"scene: {obstacles: [{kind: person, range_m: 5, azimuth_deg: 0, width_m: -1}]}\n",
            "width_m"},
           {"scene: {panel: off}\n", "needs obstacles or a hedge"},
           {"scene: {hedge: {distance_m: 20, tall: 2}}\n", "unknown key 'tall'"},
       }) {
    ProtocolParams p;
    std::string sensor, why;
    EXPECT_FALSE(ParseProtocolYaml(c.yaml, &p, &sensor, &why)) << c.yaml;
    EXPECT_NE(why.find(c.says), std::string::npos) << c.yaml << " -> " << why;
  }
}

TEST(ObstacleScene, RenderedPersonHasItsDepth) {
  SimParams p;
  p.protocol.scene = WithObstacles();
  p.sensor.fallback.sigma_d_px = 0.0;
  p.sensor.fallback.invalid_prob = 0.0;
  const Cell cell = MakeCells(p.protocol)[0];
  const StereoSim sim(p, cell);
  records::DepthFrame f;
  sim.Render(0, &f);
  const Eigen::Vector3d face = PlaceObstacles(p.protocol.scene)[0].face_center_m;
  const auto& in = p.sensor.intrinsics;
  const int u = static_cast<int>(std::lround(in.ppx + in.fx * face.x() / face.z()));
  const int v = static_cast<int>(std::lround(in.ppy + in.fy * face.y() / face.z()));
  // Quantized to 1/32 px of disparity: a few centimetres at 8 m.
  EXPECT_NEAR(f.DepthAt(u, v), face.z(), 0.05);
}

}  // namespace
}  // namespace depthbias::sim
