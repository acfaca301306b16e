#include "io/weights_yaml.h"

#include <cmath>

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

}  // namespace
}  // namespace depthbias::io
