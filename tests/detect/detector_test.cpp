// The detector on frames the simulator renders: people found where they stand, ground found
// whatever the camera's height and pitch, clusters that stay whole at 15 m and apart from a bush
// beside them, the corrected range being the bias model's, zones from the stopping distance.
#include "detect/detector.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>

#include "detect/json.h"
#include "scene_fixture.h"

namespace depthbias::detect {
namespace {

using testing::Bush;
using testing::Person;

const DetectedObstacle* Near(const FrameDetections& d, double range_m, double azimuth_deg) {
  const DetectedObstacle* best = nullptr;
  double best_gap = 0.6;  // lateral [m]
  for (const auto& o : d.obstacles) {
    const double gap = std::fabs(o.azimuth_deg - azimuth_deg) * M_PI / 180.0 * range_m;
    if (gap < best_gap && std::fabs(o.range_m - range_m) < 1.0) {
      best_gap = gap;
      best = &o;
    }
  }
  return best;
}

int CountNear(const FrameDetections& d, double range_m, double azimuth_deg, double lateral_m) {
  int n = 0;
  for (const auto& o : d.obstacles) {
    const double gap = std::fabs(o.azimuth_deg - azimuth_deg) * M_PI / 180.0 * range_m;
    n += gap < lateral_m && std::fabs(o.range_m - range_m) < 1.5;
  }
  return n;
}

TEST(ObstacleDetector, FindsPeopleAndGroundOfAnUnbiasedCamera) {
  const auto p = testing::Scene({Person(4, -20), Person(8, 5), Person(12, 25), Bush(6, 20)});
  const model::BiasModel bias(testing::Weights(0.0, 1.0));
  ObstacleDetector detector(p.sensor.intrinsics, DetectorParams{}, bias.Scenario("daylight", "HD"));
  const auto frames = testing::Render(p, 3);
  for (size_t k = 0; k < frames.size(); ++k) {
    const FrameDetections d = detector.Detect(frames[k], k);
    ASSERT_TRUE(d.success) << d.message;
    EXPECT_EQ(d.frame, k);
    EXPECT_TRUE(d.ground_found);
    // Ground 1 m below the camera, normal up (−y).
    EXPECT_NEAR(d.ground[1], -1.0, 0.01);
    EXPECT_NEAR(d.ground[3], 1.0, 0.03);
    for (const auto& [range, azimuth] : std::vector<std::pair<double, double>>{
             {4, -20}, {8, 5}, {12, 25}}) {
      const DetectedObstacle* o = Near(d, range, azimuth);
      ASSERT_NE(o, nullptr) << range << " m";
      // The median range of a 0.5 × 1.75 m front lies a little beyond its centre.
      EXPECT_NEAR(o->range_m, range, 0.01 + 0.01 * range) << range << " m";
      EXPECT_NEAR(o->azimuth_deg, azimuth, 0.5);
      EXPECT_NEAR(o->height_m, 1.75 - 0.12, 0.2);  // the ground band is removed
      EXPECT_GT(o->points, 50);
    }
    EXPECT_NE(Near(d, 6, 20), nullptr);  // the bush
    EXPECT_EQ(d.obstacles.size(), 4u);
    for (size_t i = 1; i < d.obstacles.size(); ++i)
      EXPECT_LE(d.obstacles[i - 1].range_m, d.obstacles[i].range_m);  // nearest first
  }
}

TEST(ObstacleDetector, CameraHeightAndPitchAreFree) {
  for (const auto& [height, pitch] : std::vector<std::pair<double, double>>{{1.5, 8}, {0.7, -4}}) {
    const auto p = testing::Scene({Person(6, 0), Person(10, -15)}, {}, height, pitch);
    const model::BiasModel bias(testing::Weights(0.0, 1.0));
    ObstacleDetector detector(p.sensor.intrinsics, DetectorParams{},
                              bias.Scenario("daylight", "HD"));
    const FrameDetections d = detector.Detect(testing::Render(p, 1)[0], 0);
    ASSERT_TRUE(d.ground_found) << height << " m, " << pitch << " deg";
    EXPECT_NEAR(d.ground[3], height, 0.05);
    const double tilt_deg = std::acos(-d.ground[1]) * 180.0 / M_PI;
    EXPECT_NEAR(tilt_deg, std::fabs(pitch), 0.7);
    // Ranges are to the face's centre in 3-D, whatever the pitch.
    ASSERT_NE(Near(d, 6, 0), nullptr) << height << " m, " << pitch << " deg";
    ASSERT_NE(Near(d, 10, -15), nullptr) << height << " m, " << pitch << " deg";
    EXPECT_EQ(d.obstacles.size(), 2u);
  }
}

// Stereo noise at 15 m is ~0.3 m per pixel: the tolerance grows with range, so a person there
// is one cluster, and a bush half a metre beside a person at 13 m is another.
TEST(ObstacleDetector, ToleranceGrowsWithRangeYetKeepsNeighboursApart) {
  const auto p = testing::Scene({Person(15, 10), Person(13, -21), Bush(13, -15.5)});
  const model::BiasModel bias(testing::Weights(0.0, 1.0));
  ObstacleDetector detector(p.sensor.intrinsics, DetectorParams{}, bias.Scenario("daylight", "HD"));
  for (const auto& frame : testing::Render(p, 5)) {
    const FrameDetections d = detector.Detect(frame, 0);
    EXPECT_EQ(CountNear(d, 15, 10, 1.5), 1);
    EXPECT_EQ(CountNear(d, 13, -21, 0.6), 1);
    EXPECT_EQ(CountNear(d, 13, -15.5, 0.6), 1);
  }
  // A fixed tolerance of 5 cm breaks the far person apart.
  DetectorParams fixed;
  fixed.cluster.base_tolerance_m = 0.05;
  fixed.cluster.noise_k = 0.0;
  fixed.cluster.min_points = 1;
  fixed.obstacle.min_points = 1;
  fixed.obstacle.min_height_m = 0.0;
  ObstacleDetector brittle(p.sensor.intrinsics, fixed, bias.Scenario("daylight", "HD"));
  EXPECT_GT(CountNear(brittle.Detect(testing::Render(p, 1)[0], 0), 15, 10, 1.5), 1);
}

// The corrected range is the bias model's own (ScenarioModel::CorrectedM at the cluster's
// median depth and off-axis angle), and with the unit's disparity offset it lands on the truth.
TEST(ObstacleDetector, CorrectedRangeIsTheModelsAndRemovesAKnownOffset) {
  const double delta_px = -0.25;  // far targets read farther
  const auto p = testing::Scene({Person(5, -10), Person(9, 20), Person(14, 0)},
                                {{"disparity_offset", {{"delta_px", delta_px}}}});
  const model::BiasModel bias(testing::Weights(delta_px, 1.0));
  const model::ScenarioModel& s = bias.Scenario("daylight", "HD");
  DetectorParams params;
  params.k = 2.5;
  ObstacleDetector detector(p.sensor.intrinsics, params, s);
  const FrameDetections d = detector.Detect(testing::Render(p, 1)[0], 0);
  for (const auto& [range, azimuth] : std::vector<std::pair<double, double>>{
           {5, -10}, {9, 20}, {14, 0}}) {
    const DetectedObstacle* o = Near(d, range + 0.8, azimuth);
    ASSERT_NE(o, nullptr) << range;
    EXPECT_DOUBLE_EQ(o->corrected_range_m, s.CorrectedM(o->depth_m, o->off_axis_deg));
    EXPECT_GT(o->range_m - range, 0.6 * 0.25 * range * range / 60.8) << range;  // raw: farther
    EXPECT_NEAR(o->corrected_range_m, range, 0.05) << range;
    EXPECT_GE(o->std_m, s.PredictiveStdM(o->depth_m, o->off_axis_deg));
    EXPECT_DOUBLE_EQ(o->safe_range_m, o->corrected_range_m - 2.5 * o->std_m);
  }
  ASSERT_EQ(d.obstacles.size(), 3u);
  EXPECT_LT(d.obstacles[0].std_m, d.obstacles[2].std_m);  // σ grows with range
}

TEST(ObstacleDetector, SameFrameSameDetections) {
  const auto p = testing::Scene({Person(7, 0), Bush(9, 15)});
  const model::BiasModel bias(testing::Weights(0.0, 1.0));
  ObstacleDetector detector(p.sensor.intrinsics, DetectorParams{}, bias.Scenario("daylight", "HD"));
  const auto frame = testing::Render(p, 1)[0];
  EXPECT_EQ(FormatJsonLine(detector.Detect(frame, 4)), FormatJsonLine(detector.Detect(frame, 4)));
}

TEST(ObstacleDetector, RefusesBadParametersAndFramesOfAnotherSize) {
  const model::BiasModel bias(testing::Weights(0.0, 1.0));
  const auto& s = bias.Scenario("daylight", "HD");
  DetectorParams bad;
  bad.voxel.leaf_m = 0;
  EXPECT_THROW(ObstacleDetector(camera::D455::DepthIntrinsics(), bad, s), std::invalid_argument);
  bad = DetectorParams{};
  bad.zones.decel_mps2 = 0;
  EXPECT_THROW(ObstacleDetector(camera::D455::DepthIntrinsics(), bad, s), std::invalid_argument);
  ObstacleDetector detector(camera::D455::DepthIntrinsics(), DetectorParams{}, s);
  records::DepthFrame small;
  small.width = 640;
  small.height = 360;
  small.counts.assign(640 * 360, 1000);
  const FrameDetections d = detector.Detect(small, 0);
  EXPECT_FALSE(d.success);
  EXPECT_NE(d.message.find("640x360"), std::string::npos) << d.message;
  // An empty frame holds no obstacle, and it is blind: the camera saw nothing, so nothing is
  // clear.
  records::DepthFrame empty;
  empty.width = 1280;
  empty.height = 720;
  empty.counts.assign(1280 * 720, 0);
  const FrameDetections none = detector.Detect(empty, 1);
  EXPECT_TRUE(none.success);
  EXPECT_TRUE(none.obstacles.empty());
  EXPECT_TRUE(none.blind);
  EXPECT_EQ(none.zone, Zone::kStop);
}

// A frame is blind when its valid samples are fewer than cloud.min_valid_pct of them (5 % by
// default): a wall at 4 m in the top rows of the samples only, 8 of 180 sample rows (4.4 %)
// or 10 (5.6 %). Full-scale counts (65535) are no depth.
TEST(ObstacleDetector, AFrameThatShowsTooLittleIsBlindAndNeverClear) {
  const model::BiasModel bias(testing::Weights(0.0, 1.0));
  const auto& s = bias.Scenario("daylight", "HD");
  const camera::Intrinsics in = camera::D455::DepthIntrinsics();
  const auto wall_rows = [&](int sample_rows, std::uint16_t rest) {
    records::DepthFrame f;
    f.width = in.width;
    f.height = in.height;
    f.counts.assign(static_cast<size_t>(in.width) * in.height, rest);
    for (int v = 0; v < 4 * sample_rows; ++v)
      for (int u = 0; u < in.width; ++u) f.counts[static_cast<size_t>(v * in.width + u)] = 4000;
    return f;
  };
  ObstacleDetector detector(in, DetectorParams{}, s);
  const FrameDetections few = detector.Detect(wall_rows(8, 0), 0);
  EXPECT_NEAR(few.valid_pct, 100.0 * 8 / 180, 1e-9);
  EXPECT_TRUE(few.blind);
  EXPECT_EQ(few.zone, Zone::kStop);
  for (const auto& o : few.obstacles) EXPECT_EQ(o.zone, Zone::kStop);
  const FrameDetections enough = detector.Detect(wall_rows(10, 0xFFFF), 1);
  EXPECT_NEAR(enough.valid_pct, 100.0 * 10 / 180, 1e-9);
  EXPECT_FALSE(enough.blind);
  // The share is a parameter.
  DetectorParams lenient;
  lenient.cloud.min_valid_pct = 4.0;
  ObstacleDetector detector2(in, lenient, s);
  EXPECT_FALSE(detector2.Detect(wall_rows(8, 0), 0).blind);
  lenient.cloud.min_valid_pct = 101.0;
  std::string why;
  EXPECT_FALSE(lenient.IsValid(&why));
  EXPECT_NE(why.find("min_valid_pct"), std::string::npos) << why;
  // An empty scene seen whole is clear.
  const auto p = testing::Scene({});
  ObstacleDetector open(p.sensor.intrinsics, DetectorParams{}, s);
  const FrameDetections clear = open.Detect(testing::Render(p, 1)[0], 0);
  EXPECT_FALSE(clear.blind);
  EXPECT_EQ(clear.zone, Zone::kClear);
}

// A unit whose correction moves readings farther (it reads near: disparity offset +0.25 px):
// the safe range is never farther than the range the camera measured, unless asked.
TEST(ObstacleDetector, SafeRangeIsNeverBeyondTheRawRangeUnlessAsked) {
  const double delta_px = 0.25;  // targets read nearer than they are
  const auto p = testing::Scene({Person(8, -10), Person(12, 10)},
                                {{"disparity_offset", {{"delta_px", delta_px}}}});
  const model::BiasModel bias(testing::Weights(delta_px, 1.0, 0.005, 1e-5));
  const model::ScenarioModel& s = bias.Scenario("daylight", "HD");
  const auto frame = testing::Render(p, 1)[0];
  ObstacleDetector detector(p.sensor.intrinsics, DetectorParams{}, s);
  DetectorParams beyond;
  beyond.safe_beyond_raw = true;
  ObstacleDetector allowed(p.sensor.intrinsics, beyond, s);
  const FrameDetections d = detector.Detect(frame, 0), a = allowed.Detect(frame, 0);
  ASSERT_EQ(d.obstacles.size(), a.obstacles.size());
  for (const auto& [range, azimuth] : std::vector<std::pair<double, double>>{{8, -10}, {12, 10}}) {
    const DetectedObstacle* o = Near(d, range - 0.4, azimuth);
    ASSERT_NE(o, nullptr) << range;
    ASSERT_GT(o->corrected_range_m - 2.0 * o->std_m, o->range_m) << "the model moves it farther";
  }
  for (size_t i = 0; i < d.obstacles.size(); ++i) {
    const DetectedObstacle& o = d.obstacles[i];
    EXPECT_EQ(o.safe_range_m, std::min(o.range_m, o.corrected_range_m - 2.0 * o.std_m));
    EXPECT_LE(o.safe_range_m, o.range_m);
    EXPECT_DOUBLE_EQ(a.obstacles[i].safe_range_m, o.corrected_range_m - 2.0 * o.std_m);
  }
  EXPECT_NE(FormatJsonLine(a, true).find("\"safe_beyond_raw\": true"), std::string::npos);
  EXPECT_EQ(FormatJsonLine(d).find("safe_beyond_raw"), std::string::npos);
}

// The margin's σ_d is the recording's own: the temporal spread at the obstacles of consecutive
// frames recovers the simulated sensor's disparity noise, High Accuracy's and High Density's
// alike (not the configured 0.08 px); frames that do not follow each other give no pair.
TEST(ObstacleDetector, TemporalSpreadAtTheObstaclesGivesTheUnitsDisparityNoise) {
  const model::BiasModel bias(testing::Weights(0.0, 1.0));
  for (const double sigma_px : {0.05, 0.15}) {
    auto p = testing::Scene({Person(5, -10), Person(9, 15), Bush(7, 0)});
    p.sensor.fallback.sigma_d_px = sigma_px;
    ObstacleDetector detector(p.sensor.intrinsics, DetectorParams{},
                              bias.Scenario("daylight", "HD"));
    const auto frames = testing::Render(p, 8);
    for (size_t k = 0; k < frames.size(); ++k) detector.Detect(frames[k], k);
    const TemporalNoise& t = detector.temporal_noise();
    EXPECT_GT(t.pairs(), 1000) << sigma_px;
    // Within 15 %: the subpixel step (1/32 px) and the millimetre depth units add a little.
    EXPECT_NEAR(t.SigmaPx(), sigma_px, 0.15 * sigma_px);
    detector.ResetTemporalNoise();
    EXPECT_EQ(t.pairs(), 0);
    detector.Detect(frames[0], 0);
    detector.Detect(frames[1], 5);  // not the next frame
    EXPECT_EQ(t.pairs(), 0);
    // The margin takes what it is given.
    detector.SetDisparityNoisePx(sigma_px);
    EXPECT_EQ(detector.Detect(frames[2], 6).disparity_noise_px, sigma_px);
    EXPECT_THROW(detector.SetDisparityNoisePx(0.0), std::invalid_argument);
  }
}

// The weights' σ_d is a preset's: a group gives it to a recording of its own preset only (a
// group pooling presets, "*", gives none). The source goes with the value into every line.
TEST(ObstacleDetector, TheWeightsSigmaIsTheRecordingsPresetsOnly) {
  records::BiasWeightsGroup g;
  g.light = "daylight";
  g.preset = "HD";
  EXPECT_TRUE(std::isnan(WeightsDisparityNoisePx(g, "HD")));  // the weights do not say
  g.disparity_noise = {true, 0.15, 16};
  EXPECT_EQ(WeightsDisparityNoisePx(g, "HD"), 0.15);
  EXPECT_TRUE(std::isnan(WeightsDisparityNoisePx(g, "HA")));
  g.preset = "*";
  EXPECT_TRUE(std::isnan(WeightsDisparityNoisePx(g, "HD")));

  const model::BiasModel bias(testing::Weights(0.0, 1.0));
  auto p = testing::Scene({Person(5, -10)});
  ObstacleDetector detector(p.sensor.intrinsics, DetectorParams{},
                            bias.Scenario("daylight", "HD"));
  const auto frames = testing::Render(p, 1);
  FrameDetections d = detector.Detect(frames[0], 0);
  EXPECT_EQ(d.disparity_noise_from, NoiseSource::kConfig);
  EXPECT_NE(FormatJsonLine(d).find("\"disparity_noise_px\": 0.08, \"disparity_noise_from\": "
                                   "\"config\""),
            std::string::npos)
      << FormatJsonLine(d);
  detector.SetDisparityNoisePx(0.15, NoiseSource::kWeights);
  d = detector.Detect(frames[0], 1);
  EXPECT_EQ(d.disparity_noise_px, 0.15);
  EXPECT_NE(FormatJsonLine(d).find("\"disparity_noise_from\": \"weights\""), std::string::npos);
  EXPECT_EQ(NoiseSourceName(NoiseSource::kRecording), "recording");
}

TEST(Zones, StoppingDistanceAndZones) {
  ZoneParams z;
  z.speed_mps = 3.0;
  z.reaction_s = 0.4;
  z.decel_mps2 = 2.0;
  z.clearance_m = 0.5;
  z.slow_margin_m = 2.0;
  const double s = 3.0 * 0.4 + 9.0 / 4.0 + 0.5;  // v·T + v²/(2a) + C
  EXPECT_DOUBLE_EQ(z.StoppingDistanceM(), s);
  EXPECT_EQ(ZoneFor(s - 0.01, z), Zone::kStop);
  EXPECT_EQ(ZoneFor(s, z), Zone::kStop);
  EXPECT_EQ(ZoneFor(s + 1.0, z), Zone::kSlow);
  EXPECT_EQ(ZoneFor(s + 2.0, z), Zone::kSlow);
  EXPECT_EQ(ZoneFor(s + 2.01, z), Zone::kClear);
  EXPECT_EQ(ZoneFor(std::nan(""), z), Zone::kStop);
  EXPECT_EQ(ZoneName(Zone::kSlow), "slow");
}

TEST(JsonLine, HoldsTheFieldsOfDesignMd) {
  FrameDetections d;
  d.frame = 12;
  d.timestamp_s = 0.4;
  DetectedObstacle o;
  o.centroid_m = {1.0, 0.1, 7.0};
  o.azimuth_deg = 8.13;
  o.range_m = 7.1;
  o.corrected_range_m = 7.0;
  o.std_m = 0.2;
  o.safe_range_m = 6.6;
  o.zone = Zone::kClear;
  o.points = 321;
  d.obstacles = {o, o};
  d.obstacles[1].std_m = std::nan("");
  const std::string line = FormatJsonLine(d);
  ASSERT_EQ(line.back(), '\n');
  EXPECT_EQ(std::count(line.begin(), line.end(), '\n'), 1);
  const YAML::Node n = YAML::Load(line);
  EXPECT_EQ(n["frame"].as<int>(), 12);
  EXPECT_DOUBLE_EQ(n["timestamp_s"].as<double>(), 0.4);
  ASSERT_EQ(n["obstacles"].size(), 2u);
  const YAML::Node a = n["obstacles"][0];
  EXPECT_EQ(a.size(), 8u);
  EXPECT_DOUBLE_EQ(a["centroid_m"][2].as<double>(), 7.0);
  EXPECT_DOUBLE_EQ(a["azimuth_deg"].as<double>(), 8.13);
  EXPECT_DOUBLE_EQ(a["range_m"].as<double>(), 7.1);
  EXPECT_DOUBLE_EQ(a["corrected_range_m"].as<double>(), 7.0);
  EXPECT_DOUBLE_EQ(a["std_m"].as<double>(), 0.2);
  EXPECT_DOUBLE_EQ(a["safe_range_m"].as<double>(), 6.6);
  EXPECT_EQ(a["zone"].as<std::string>(), "clear");
  EXPECT_EQ(a["points"].as<int>(), 321);
  EXPECT_NE(line.find("\"std_m\": null"), std::string::npos) << line;  // not NaN: JSON has none
  EXPECT_EQ(n["status"].as<std::string>(), "ok");
  EXPECT_EQ(n["zone"].as<std::string>(), "clear");
}

// Numbers written are the numbers computed: whatever their magnitude, read back they are the
// same to 6 significant digits (a 64-byte buffer once turned 1e308 into -7.3e61), and a
// timestamp keeps its microseconds.
TEST(JsonLine, NumbersKeepTheirMagnitude) {
  FrameDetections d;
  d.timestamp_s = 1732412345.678901;
  d.valid_pct = 37.5;
  d.blind = true;
  d.zone = Zone::kStop;
  DetectedObstacle o;
  o.centroid_m = {-1e-300, 2.5e-7, 1e300};
  o.range_m = 1e308;
  o.corrected_range_m = -1e308;
  o.std_m = 123456789.0;
  o.safe_range_m = -7.25e61;
  d.obstacles = {o};
  const std::string line = FormatJsonLine(d);
  const YAML::Node n = YAML::Load(line);
  EXPECT_NEAR(n["timestamp_s"].as<double>(), 1732412345.678901, 1e-6) << line;
  EXPECT_EQ(n["status"].as<std::string>(), "blind");
  EXPECT_EQ(n["valid_pct"].as<double>(), 37.5);
  EXPECT_EQ(n["zone"].as<std::string>(), "stop");
  const YAML::Node a = n["obstacles"][0];
  const auto same = [](double written, double computed) {
    return std::fabs(written - computed) <= 1e-5 * std::fabs(computed);
  };
  EXPECT_TRUE(same(a["centroid_m"][0].as<double>(), -1e-300)) << line;
  EXPECT_TRUE(same(a["centroid_m"][1].as<double>(), 2.5e-7)) << line;
  EXPECT_TRUE(same(a["centroid_m"][2].as<double>(), 1e300)) << line;
  EXPECT_TRUE(same(a["range_m"].as<double>(), 1e308)) << line;
  EXPECT_TRUE(same(a["corrected_range_m"].as<double>(), -1e308)) << line;
  EXPECT_TRUE(same(a["std_m"].as<double>(), 123456789.0)) << line;
  EXPECT_TRUE(same(a["safe_range_m"].as<double>(), -7.25e61)) << line;
}

}  // namespace
}  // namespace depthbias::detect
