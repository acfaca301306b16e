// panel extraction on field scenes (field_scene.h): a panel on a post over rough grass, seen by a
// pitched camera, beside a bush, a person and a hedge, with 97–99 % holes on the panel. Held to:
// median within one disparity quantization step (+0.1 %) of the panel's own valid samples, hole
// rate within 1 point, azimuth within 0.5°, tilt within 2°, height and width within 0.1 m, with
// and without the manifest's search window.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "field_scene.h"
#include "panel/extract.h"

namespace depthbias::panel {
namespace {

using test::FieldScene;
using test::FieldSpec;

class FieldSource : public FrameSource {
 public:
  explicit FieldSource(const FieldScene* scene) : scene_(scene) {}
  bool Next(records::DepthFrame* f) override {
    if (k_ >= scene_->frames.size()) return false;
    *f = scene_->frames[k_++];
    return true;
  }
  bool Rewind() override {
    k_ = 0;
    return true;
  }

 private:
  const FieldScene* scene_;
  std::size_t k_ = 0;
};

FieldSpec Spec(const std::string& name, double distance_m, double angle_deg, double holes) {
  FieldSpec s;
  s.name = name;
  s.distance_m = distance_m;
  s.angle_deg = angle_deg;
  s.panel_hole_rate = holes;
  s.seed = static_cast<std::uint64_t>(distance_m * 100 + angle_deg + holes * 1000);
  return s;
}

std::vector<FieldSpec> Scenes() {
  std::vector<FieldSpec> out;
  for (double d : {4.0, 8.0, 12.0, 16.0}) {
    for (double a : {0.0, 20.0, 35.0}) {
      const std::string tag = std::to_string(static_cast<int>(d)) + "m_" +
                              std::to_string(static_cast<int>(a)) + "deg";
      out.push_back(Spec("HA_" + tag, d, a, 0.97));   // High Accuracy: 97 % holes
      out.push_back(Spec("HD_" + tag, d, a, 0.40));   // High Density
    }
  }
  FieldSpec s = Spec("HA99_person_4m_10deg", 4, 10, 0.99);
  s.person = true;
  out.push_back(s);
  s = Spec("HA99_person_16m_20deg", 16, 20, 0.99);
  s.person = true;
  out.push_back(s);
  s = Spec("valid1pct_5frames_8m_0deg", 8, 0, 0.99);
  s.frames = 5;
  out.push_back(s);
  s = Spec("valid1pct_5frames_16m_20deg", 16, 20, 0.99);
  s.frames = 5;
  out.push_back(s);
  s = Spec("noisy16m_6frames_HD_0deg", 16, 0, 0.40);  // σ_d 0.15 px: ~0.6 m per pixel at 16 m
  s.noise_px = 0.15;
  s.frames = 6;
  out.push_back(s);
  s = Spec("noisy16m_6frames_HD_35deg", 16, 35, 0.40);
  s.noise_px = 0.15;
  s.frames = 6;
  out.push_back(s);
  s = Spec("roll3_pitch0_yaw3_12m_10deg", 12, 10, 0.97);
  s.roll_deg = 3;
  s.pitch_deg = 0;
  s.panel_yaw_deg = 3;
  out.push_back(s);
  s = Spec("yaw0_nobush_4m_0deg", 4, 0, 0.98);
  s.panel_yaw_deg = 0;
  s.bush = false;
  out.push_back(s);
  return out;
}

struct Case {
  FieldSpec spec;
  bool with_window;
};

class FieldInMemory : public ::testing::TestWithParam<Case> {};

TEST_P(FieldInMemory, FoundAndMeasuredWithinTolerance) {
  const Case& c = GetParam();
  const FieldScene scene(c.spec);
  FieldSource source(&scene);
  SearchWindow window;
  if (c.with_window) {
    window.distance_m = c.spec.distance_m;
    window.angle_deg = c.spec.angle_deg;
  }
  const ExtractResult r = ExtractPanel(source, scene.in, PanelParams{}, window);
  ASSERT_EQ(r.metrics.status, "ok") << r.metrics.message;
  const records::PanelMetrics& m = r.metrics;
  const double z = scene.true_median_m;
  const double step_m = z * z / 32.0 / (scene.in.fx * camera::D455::kBaselineM);
  // The region must lie on the panel: every region pixel is a panel pixel.
  int off_panel = 0;
  for (std::uint32_t i : r.region.pixels) off_panel += scene.surface[i] != FieldScene::kPanel;
  EXPECT_EQ(off_panel, 0) << "region pixels off the panel";
  EXPECT_NEAR(m.median_m, z, step_m + 0.001 * z);
  EXPECT_NEAR(m.hole_rate_pct, scene.true_hole_rate_pct, 1.0);
  EXPECT_NEAR(m.azimuth_deg, scene.true_azimuth_deg, 0.5);
  // Tilt within 2°, or within four of its own standard errors where the recording cannot resolve
  // 2° (far panels with 97–99 % holes: a few hundred samples carry the slope; with 80 samples
  // the linearized σ understates the spread of the tilt's magnitude).
  const double tilt_tol_deg = std::max(2.0, 4.0 * r.measure.tilt_sigma_deg);
  EXPECT_NEAR(m.normal_tilt_deg, scene.true_tilt_deg, tilt_tol_deg);
  EXPECT_NEAR(m.panel_height_m, 1.0, 0.1);
  EXPECT_NEAR(m.panel_width_m, 1.0, 0.1);
  if (std::getenv("DEPTHBIAS_PRINT_FIELD"))
    std::printf("%-30s %s median %+7.1f mm (step %.0f) holes %+5.2f az %+5.2f tilt %5.2f/%5.2f "
                "(σ %.2f) w %.3f h %.3f region %zu excluded %d\n",
                c.spec.name.c_str(), c.with_window ? "window" : "free  ",
                1000 * (m.median_m - z), 1000 * step_m, m.hole_rate_pct - scene.true_hole_rate_pct,
                m.azimuth_deg - scene.true_azimuth_deg, m.normal_tilt_deg, scene.true_tilt_deg,
                r.measure.tilt_sigma_deg,
                m.panel_width_m, m.panel_height_m, r.region.size(), r.excluded_pixels);
}

std::vector<Case> Cases() {
  std::vector<Case> out;
  for (const FieldSpec& s : Scenes()) {
    out.push_back({s, true});
    out.push_back({s, false});
  }
  return out;
}

INSTANTIATE_TEST_SUITE_P(Scenes, FieldInMemory, ::testing::ValuesIn(Cases()),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           return info.param.spec.name +
                                  (info.param.with_window ? "_manifest" : "_free");
                         });

}  // namespace
}  // namespace depthbias::panel
