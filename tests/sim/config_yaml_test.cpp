// The simulator's YAML documents: the committed protocol and sensor load; unknown keys, effect
// names, parameters and wrong types are refused with a reason naming them.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "gap/calibrate.h"
#include "sim/config_yaml.h"

namespace depthbias::sim {
namespace {

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(ConfigYaml, CommittedProtocolIsTheArticles) {
  const std::string text = ReadText(DEPTHBIAS_SOURCE_DIR "/config/protocol_paper.yaml");
  ASSERT_FALSE(text.empty());
  ProtocolParams p;
  std::string sensor, why;
  ASSERT_TRUE(ParseProtocolYaml(text, &p, &sensor, &why)) << why;
  EXPECT_EQ(MakeCells(p).size(), 128u);
  EXPECT_EQ(p.distance_is, DistanceIs::kRange);
  EXPECT_EQ(p.distances_m, (std::vector<double>{4, 8, 12, 16}));
  EXPECT_EQ(p.angles_deg, (std::vector<double>{0, 10, 20, 35}));
  EXPECT_EQ(p.emitters, (std::vector<bool>{false, true}));
  EXPECT_EQ(sensor, "sensor_calibrated.yaml");
}

TEST(ConfigYaml, CommittedCalibratedSensorLoadsWithEveryScenario) {
  const std::string text = ReadText(DEPTHBIAS_SOURCE_DIR "/config/sensor_calibrated.yaml");
  ASSERT_FALSE(text.empty());
  SensorParams s;
  std::string why;
  ASSERT_TRUE(ParseSensorYaml(text, &s, &why)) << why;
  ASSERT_EQ(s.scenarios.size(), 4u);
  for (const char* light : {"daylight", "sunset"})
    for (const char* preset : {"HA", "HD"}) {
      bool found = false;
      const ScenarioParams sc = s.Scenario(light, preset, &found);
      EXPECT_TRUE(found) << light << " " << preset;
      EXPECT_GT(sc.sigma_d_px, 0.0);
      EXPECT_LE(sc.sigma_d_px, gap::CalibrateParams{}.max_sigma_d_px + 1e-9);
    }
}

TEST(ConfigYaml, SensorRoundTrips) {
  SensorParams s;
  s.baseline_m = 0.05;
  s.scenarios = {{"daylight", "HA", 0.07, 0.6}, {"sunset", "HD", 0.11, 0.3}};
  SensorParams back;
  std::string why;
  ASSERT_TRUE(ParseSensorYaml(FormatSensorYaml(s, {"a comment"}), &back, &why)) << why;
  EXPECT_EQ(back.baseline_m, 0.05);
  ASSERT_EQ(back.scenarios.size(), 2u);
  EXPECT_EQ(back.scenarios[1].preset, "HD");
  EXPECT_DOUBLE_EQ(back.scenarios[1].sigma_d_px, 0.11);
}

TEST(ConfigYaml, OnlyNamedKeysOverride) {
  ProtocolParams p;
  std::string sensor, why;
  ASSERT_TRUE(ParseProtocolYaml("protocol: {frames: 7}\n", &p, &sensor, &why)) << why;
  EXPECT_EQ(p.frames, 7);
  EXPECT_EQ(p.distances_m.size(), 4u);
  EXPECT_TRUE(sensor.empty());
}

TEST(ConfigYaml, RefusesUnknownKeysAndWrongTypes) {
  ProtocolParams p;
  std::string sensor, why;
  EXPECT_FALSE(ParseProtocolYaml("protocol: {frame: 7}\n", &p, &sensor, &why));
  EXPECT_NE(why.find("frame"), std::string::npos) << why;
  EXPECT_FALSE(ParseProtocolYaml("protocol: {distances_m: [4, far]}\n", &p, &sensor, &why));
  EXPECT_NE(why.find("distances_m[1]"), std::string::npos) << why;
  EXPECT_FALSE(ParseProtocolYaml("protocol: {distance_is: slant}\n", &p, &sensor, &why));
  EXPECT_NE(why.find("distance_is"), std::string::npos) << why;
  EXPECT_FALSE(ParseProtocolYaml("protocol: {frames: 2.5}\n", &p, &sensor, &why));
  EXPECT_FALSE(ParseProtocolYaml("scene: {camera_height_m: -1}\n", &p, &sensor, &why));
  EXPECT_NE(why.find("camera_height_m"), std::string::npos) << why;
  EXPECT_FALSE(ParseProtocolYaml("protocol: [\n", &p, &sensor, &why));
  EXPECT_NE(why.find("YAML"), std::string::npos) << why;
  SensorParams s;
  EXPECT_FALSE(ParseSensorYaml("sensor: {baseline_m: wide}\n", &s, &why));
  EXPECT_NE(why.find("sensor.baseline_m"), std::string::npos) << why;
  EXPECT_FALSE(ParseSensorYaml("sensor: {scenarios: [{light: x, preset: HA, sigma: 1}]}\n", &s,
                               &why));
  EXPECT_NE(why.find("sigma"), std::string::npos) << why;
}

TEST(ConfigYaml, EffectsListIsCheckedAgainstTheRegistry) {
  std::vector<EffectSpec> e;
  std::string why;
  ASSERT_TRUE(ParseEffectsYaml(
      "effects: [{name: disparity_offset, delta_px: 0.2}, {name: panel_tilt, yaw_deg: 10}]\n", &e,
      &why))
      << why;
  ASSERT_EQ(e.size(), 2u);
  EXPECT_EQ(e[0].params.at("delta_px"), 0.2);
  EXPECT_TRUE(ParseEffectsYaml("effects: []\n", &e, &why)) << why;
  EXPECT_TRUE(e.empty());

  EXPECT_FALSE(ParseEffectsYaml("effects: [{name: lens_flare}]\n", &e, &why));
  EXPECT_NE(why.find("unknown effect 'lens_flare'"), std::string::npos) << why;
  EXPECT_FALSE(ParseEffectsYaml("effects: [{name: disparity_offset, delta_px: big}]\n", &e, &why));
  EXPECT_NE(why.find("effects[0].delta_px: expected a number"), std::string::npos) << why;
  EXPECT_FALSE(ParseEffectsYaml("effects: [{name: disparity_offset, delta_px: [1]}]\n", &e, &why));
  EXPECT_FALSE(ParseEffectsYaml("effects: [{name: depth_scale, gain: 2}]\n", &e, &why));
  EXPECT_NE(why.find("unknown parameter 'gain'"), std::string::npos) << why;
  EXPECT_FALSE(ParseEffectsYaml("effects: [{delta_px: 0.1}]\n", &e, &why));
  EXPECT_NE(why.find("no name"), std::string::npos) << why;
  EXPECT_FALSE(ParseEffectsYaml("effects: {name: depth_scale}\n", &e, &why));
  EXPECT_FALSE(ParseEffectsYaml("effect: []\n", &e, &why));
  EXPECT_FALSE(ParseEffectsYaml("effects: [{name: panel_tilt, yaw_deg: 95}]\n", &e, &why));
  EXPECT_NE(why.find("yaw_deg"), std::string::npos) << why;
}

TEST(ConfigYaml, RecordingOverridesTheCamera) {
  SensorParams s;
  camera::Intrinsics in = camera::D455::DepthIntrinsics();
  in.width = 848;
  in.height = 480;
  in.fx = in.fy = 424.0;
  in.ppx = 424;
  in.ppy = 240;
  ApplyRecording(in, 0.0001, {{"Stereo_Baseline", 94.5}}, &s);
  EXPECT_EQ(s.intrinsics.width, 848);
  EXPECT_DOUBLE_EQ(s.depth_units_m, 0.0001);
  EXPECT_DOUBLE_EQ(s.baseline_m, 0.0945);
  EXPECT_EQ(s.intrinsics.model, camera::Distortion::kNone);
  // 25 m does not fit 16-bit counts at 0.1 mm: the range is the camera's, 6.5535 m.
  EXPECT_DOUBLE_EQ(s.max_depth_m, 65535 * 0.0001);
  std::string why;
  EXPECT_TRUE(s.IsValid(&why)) << why;
  s.max_depth_m = 25;
  EXPECT_FALSE(s.IsValid(&why));
  EXPECT_NE(why.find("at most 6.5535 m"), std::string::npos) << why;
}

}  // namespace
}  // namespace depthbias::sim
