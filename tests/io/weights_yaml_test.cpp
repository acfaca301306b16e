#include "io/weights_yaml.h"

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace depthbias::io {
namespace {

records::BiasWeights Example() {
  records::BiasWeights w;
  w.model = "disp_knots";
  w.lambda = 0.001;
  w.loss = "huber";
  w.focal_px = 640;
  w.baseline_m = 0.095;
  w.group_by = {"light", "preset"};
  records::BiasWeightsGroup g;
  g.light = "daylight";
  g.preset = "HA";
  g.n = 32;
  g.names = {"delta_px", "k_0deg", "k_35deg"};
  g.values = {0.1 + 0.2, -1e-17, 123456.789};
  g.knots_deg = {0, 35};
  g.rmse_m = 0.3;
  g.mae_m = 0.2;
  g.residual_std_m = 0.31;
  g.cv = {{"point", 0.5, 0.4}, {"distance", 0.6, 0.45}};
  g.covariance = {{1, 0.1, 0}, {0.1, 2, 0}, {0, 0, 3}};
  w.groups = {g, g};
  w.groups[1].preset = "HD";
  w.groups[1].emitter = "on";
  w.input_file = "in, with comma.csv";
  w.input_sha256 = std::string(64, 'a');
  w.tool = "fit_bias";
  w.tool_version = "0.1.0";
  return w;
}

TEST(WeightsYaml, RoundTripsExactly) {
  const auto w = Example();
  const auto back = ParseWeightsYaml(FormatWeightsYaml(w), "w.yaml");
  EXPECT_EQ(back.model, w.model);
  EXPECT_EQ(back.group_by, w.group_by);
  ASSERT_EQ(back.groups.size(), 2u);
  EXPECT_EQ(back.groups[0].names, w.groups[0].names);
  EXPECT_EQ(back.groups[0].values, w.groups[0].values);  // shortest round-trip numbers
  EXPECT_EQ(back.groups[0].knots_deg, w.groups[0].knots_deg);
  EXPECT_EQ(back.groups[0].covariance, w.groups[0].covariance);
  EXPECT_EQ(back.groups[0].emitter, "*");
  EXPECT_EQ(back.groups[1].emitter, "on");
  ASSERT_EQ(back.groups[0].cv.size(), 2u);
  EXPECT_EQ(back.groups[0].cv[1].scheme, "distance");
  EXPECT_EQ(back.input_file, w.input_file);
  EXPECT_EQ(back.tool_version, "0.1.0");
}

std::string ErrorOf(const std::string& text) {
  try {
    ParseWeightsYaml(text, "w.yaml");
  } catch (const IoError& e) {
    return e.what();
  }
  return "";
}

TEST(WeightsYaml, OtherSchemasAndWrongTypesAreNamed) {
  EXPECT_NE(ErrorOf("a: 1\n").find("not a depthbias weights file"), std::string::npos);
  EXPECT_NE(ErrorOf("- 1\n- 2\n").find("not a depthbias weights file"), std::string::npos);
  EXPECT_NE(ErrorOf("a: [1, 2\n").find("not valid YAML"), std::string::npos);
  std::string text = FormatWeightsYaml(Example());
  std::string bad = text;
  bad.replace(bad.find("k_0deg: "), 8 + 6, "k_0deg: small");
  const std::string e = ErrorOf(bad);
  EXPECT_NE(e.find("groups[0].weights.k_0deg"), std::string::npos) << e;
  EXPECT_NE(e.find("w.yaml"), std::string::npos) << e;
  bad = text;
  bad.replace(bad.find("lambda: 0.001"), 13, "lambda: [1]");
  EXPECT_NE(ErrorOf(bad).find("'lambda'"), std::string::npos) << ErrorOf(bad);
  bad = text;
  bad.replace(bad.find("model: disp_knots\n"), 18, "");
  EXPECT_NE(ErrorOf(bad).find("'model': missing"), std::string::npos) << ErrorOf(bad);
}

// A misspelt key must not be ignored, at the top, in a group or in the provenance.
TEST(WeightsYaml, UnknownKeysAreNamed) {
  const std::string text = FormatWeightsYaml(Example());
  std::string bad = "bogus_key: 1\n" + text;
  EXPECT_NE(ErrorOf(bad).find("key 'bogus_key': unknown key"), std::string::npos) << ErrorOf(bad);
  bad = text;
  bad.replace(bad.find("rmse_m:"), 7, "rsme_m:");
  EXPECT_NE(ErrorOf(bad).find("'groups[0].rsme_m': unknown key"), std::string::npos)
      << ErrorOf(bad);
  bad = text;
  bad.replace(bad.find("tool_version:"), 13, "tool_versoin:");
  EXPECT_NE(ErrorOf(bad).find("'provenance.tool_versoin': unknown key"), std::string::npos)
      << ErrorOf(bad);
  EXPECT_EQ(ErrorOf(text), "");
}

// The unit's disparity noise per group: written where known, read back exactly; weights
// written before it (or from tables that did not measure it) read with it unknown.
TEST(WeightsYaml, DisparityNoiseRoundTripsAndIsOptional) {
  auto w = Example();
  w.groups[1].disparity_noise = {true, 0.15016384726, 16};
  const std::string text = FormatWeightsYaml(w);
  EXPECT_NE(text.find("disparity_noise: {sigma_px: 0.15016384726, recordings: 16}"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("disparity_noise"), text.rfind("disparity_noise")) << "group 0 has none";
  const auto back = ParseWeightsYaml(text, "w.yaml");
  EXPECT_FALSE(back.groups[0].disparity_noise.known);
  ASSERT_TRUE(back.groups[1].disparity_noise.known);
  EXPECT_EQ(back.groups[1].disparity_noise.sigma_px, 0.15016384726);
  EXPECT_EQ(back.groups[1].disparity_noise.recordings, 16);
  // Without the key (a file of before): loads, nothing known.
  const auto old = ParseWeightsYaml(FormatWeightsYaml(Example()), "old.yaml");
  for (const auto& g : old.groups) EXPECT_FALSE(g.disparity_noise.known);
}

// A σ_d that is not a positive number of pixels, or a count that is not one, is refused in one
// line naming the file and the key.
TEST(WeightsYaml, BadDisparityNoiseIsRefusedNamingTheKey) {
  auto w = Example();
  w.groups[0].disparity_noise = {true, 0.07, 16};
  const std::string text = FormatWeightsYaml(w);
  const std::string good = "disparity_noise: {sigma_px: 0.07, recordings: 16}";
  ASSERT_NE(text.find(good), std::string::npos) << text;
  const std::string key = "groups[0].disparity_noise";
  for (const auto& [value, says] : std::vector<std::pair<std::string, std::string>>{
           {"{sigma_px: small, recordings: 16}", key + ".sigma_px': 'small' is not a number"},
           {"{sigma_px: -0.07, recordings: 16}", key + ".sigma_px': -0.07 is outside (0, 100] px"},
           {"{sigma_px: 0, recordings: 16}", key + ".sigma_px': 0 is outside (0, 100] px"},
           {"{sigma_px: .nan, recordings: 16}", key + ".sigma_px': nan is not a finite number"},
           {"{sigma_px: .inf, recordings: 16}", key + ".sigma_px': inf is not a finite number"},
           {"{sigma_px: 1e9, recordings: 16}", key + ".sigma_px': 1e+09 is outside (0, 100] px"},
           {"{sigma_px: [0.07], recordings: 16}", key + ".sigma_px': expected a number"},
           {"{sigma_px: 0.07, recordings: 0}", key + ".recordings': 0 recordings"},
           {"{sigma_px: 0.07, recordings: 2.5}", key + ".recordings': '2.5' is not an integer"},
           {"{sigma_px: 0.07}", key + ".recordings': missing"},
           {"{recordings: 16}", key + ".sigma_px': missing"},
           {"{sigma_px: 0.07, recordings: 16, sigma: 1}", key + ".sigma': unknown key"},
           {"0.07", key + "': expected a map {sigma_px, recordings}"}}) {
    std::string bad = text;
    bad.replace(bad.find(good) + 17, good.size() - 17, value);
    const std::string e = ErrorOf(bad);
    EXPECT_EQ(e.rfind("w.yaml: key '", 0), 0u) << value << " -> " << e;
    EXPECT_NE(e.find(says), std::string::npos) << value << " -> " << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  }
}

}  // namespace
}  // namespace depthbias::io
