// The detector's YAML: the committed config loads and states the struct's defaults; unknown keys,
// wrong types and invalid values are refused with a reason naming the key.
#include "detect/config_yaml.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

namespace depthbias::detect {
namespace {

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(DetectorYaml, CommittedConfigListsTheDefaults) {
  const std::string text = ReadText(DEPTHBIAS_SOURCE_DIR "/config/obstacle_detector.yaml");
  ASSERT_FALSE(text.empty());
  DetectorParams p;
  p.k = 99;  // every key of the file is applied
  std::string why;
  ASSERT_TRUE(ParseDetectorYaml(text, &p, &why)) << why;
  const DetectorParams d;
  EXPECT_EQ(p.cloud.stride_px, d.cloud.stride_px);
  EXPECT_EQ(p.cloud.max_range_m, d.cloud.max_range_m);
  EXPECT_EQ(p.voxel.leaf_m, d.voxel.leaf_m);
  EXPECT_EQ(p.ground.max_tilt_deg, d.ground.max_tilt_deg);
  EXPECT_EQ(p.ground.distance_m, d.ground.distance_m);
  EXPECT_EQ(p.cluster.base_tolerance_m, d.cluster.base_tolerance_m);
  EXPECT_EQ(p.cluster.noise_k, d.cluster.noise_k);
  EXPECT_EQ(p.obstacle.min_height_m, d.obstacle.min_height_m);
  EXPECT_EQ(p.zones.StoppingDistanceM(), d.zones.StoppingDistanceM());
  EXPECT_EQ(p.k, d.k);
  EXPECT_EQ(p.cloud.min_valid_pct, d.cloud.min_valid_pct);
  EXPECT_EQ(p.safe_beyond_raw, d.safe_beyond_raw);
  EXPECT_EQ(p.voxel.use_pcl, d.voxel.use_pcl);
  EXPECT_EQ(p.cluster.use_pcl, d.cluster.use_pcl);
}

TEST(DetectorYaml, OverridesOnlyWhatItNames) {
  DetectorParams p;
  std::string why;
  ASSERT_TRUE(ParseDetectorYaml("zones: {speed_mps: 4}\nk: 3\ncloud: {min_valid_pct: 12}\n"
                                "safe_beyond_raw: true\n",
                                &p, &why))
      << why;
  EXPECT_EQ(p.zones.speed_mps, 4.0);
  EXPECT_EQ(p.k, 3.0);
  EXPECT_EQ(p.cloud.min_valid_pct, 12.0);
  EXPECT_TRUE(p.safe_beyond_raw);
  EXPECT_EQ(p.zones.decel_mps2, DetectorParams{}.zones.decel_mps2);
}

TEST(DetectorYaml, BadDocumentsAreRefusedNamingTheKey) {
  struct Case {
    std::string yaml, says;
  };
  for (const Case& c : std::vector<Case>{
           {"cluster: {tolerance_m: 0.3}\n", "cluster.tolerance_m"},
           {"speed: 3\n", "unknown key 'speed'"},
           {"voxel: {leaf_m: small}\n", "voxel.leaf_m: expected a number"},
           {"cloud: {stride_px: 2.5}\n", "cloud.stride_px"},
           {"ground: {enabled: maybe}\n", "ground.enabled"},
           {"zones: {decel_mps2: 0}\n", "zones.decel_mps2"},
           {"k: -1\n", "k must be in (0, 10]"},
           {"k: 0\n", "k must be in (0, 10]"},
           {"k: 10.5\n", "k must be in (0, 10]"},
           {"cloud: {min_valid_pct: 150}\n", "cloud.min_valid_pct"},
           {"safe_beyond_raw: 2\n", "safe_beyond_raw"},
           {"cloud: [1, 2]\n", "cloud: expected a map"},
           {"{unclosed\n", "not valid YAML"},
           {"", "empty"},
       }) {
    DetectorParams p;
    const DetectorParams before = p;
    std::string why;
    EXPECT_FALSE(ParseDetectorYaml(c.yaml, &p, &why)) << c.yaml;
    EXPECT_NE(why.find(c.says), std::string::npos) << c.yaml << " -> " << why;
    EXPECT_EQ(p.k, before.k);  // untouched on failure
  }
}

}  // namespace
}  // namespace depthbias::detect
