#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "camera/intrinsics.h"
#include "metrics/geometry.h"
#include "metrics/panel_pixels.h"
#include "panel/extract.h"
#include "synthetic_scene.h"

namespace depthbias::panel {
namespace {

using test::Scene;
using test::SceneSpec;

class VectorSource : public FrameSource {
 public:
  explicit VectorSource(const Scene* scene) : scene_(scene) {}
  bool Next(records::DepthFrame* f) override {
    if (k_ >= scene_->spec.frames) return false;
    *f = scene_->Frame(k_++);
    return true;
  }
  bool Rewind() override {
    k_ = 0;
    ++rewinds;
    return true;
  }
  int rewinds = 0;

 private:
  const Scene* scene_;
  int k_ = 0;
};

double IoU(const metrics::PanelRegion& region, const std::vector<char>& footprint) {
  std::vector<char> mask(footprint.size(), 0);
  for (std::uint32_t i : region.pixels) mask[i] = 1;
  std::size_t inter = 0, uni = 0;
  for (std::size_t i = 0; i < mask.size(); ++i) {
    inter += mask[i] && footprint[i];
    uni += mask[i] || footprint[i];
  }
  return uni ? static_cast<double>(inter) / uni : 0.0;
}

// Depth step of one 1/32 px disparity step at depth Z: ΔZ = Z²·Δd / (f·B).
double QuantStep(double z, double fx) { return z * z / 32.0 / (fx * camera::D455::kBaselineM); }

TEST(PanelParams, DefaultsAreValidAndBadValuesAreRefused) {
  PanelParams p;
  std::string why;
  EXPECT_TRUE(p.IsValid(&why)) << why;
  EXPECT_TRUE(p.Set("panel_width_m", "1.2", &why));
  EXPECT_DOUBLE_EQ(p.panel_width_m, 1.2);
  EXPECT_FALSE(p.Set("panel_widht_m", "1", &why));
  EXPECT_NE(why.find("unknown"), std::string::npos);
  EXPECT_FALSE(p.Set("seed", "abc", &why));
  p.size_tolerance = 2;
  EXPECT_FALSE(p.IsValid(&why));
}

TEST(PanelGeometry, PlaneFitRecoversKnownPlane) {
  metrics::PlaneMoments m;
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.2, -1).normalized();
  const Eigen::Vector3d c(0.5, 0.2, 6.0);
  const Eigen::Vector3d a = n.unitOrthogonal(), b = n.cross(a);
  for (int i = -5; i <= 5; ++i)
    for (int j = -5; j <= 5; ++j) m.Add(c + 0.1 * i * a + 0.1 * j * b + ((i + j) % 2 ? 0.01 : -0.01) * n);
  const metrics::PlaneFit f = metrics::FitPlane(m);
  ASSERT_TRUE(f.ok);
  EXPECT_NEAR(std::fabs(f.plane.normal.dot(n)), 1.0, 1e-9);
  EXPECT_GT(f.plane.normal.dot(-c), 0);
  EXPECT_NEAR(f.rms_m, 0.01, 1e-3);
}

struct Point {
  double distance_m, angle_deg, hole_rate;
  int frames;  // enough valid samples for the normal (scripts/make_panel_bags.py, frames_for)
};

class PanelAtTestPoint : public ::testing::TestWithParam<Point> {};

TEST_P(PanelAtTestPoint, FoundAndMeasuredWithinTolerance) {
  SceneSpec s;
  s.distance_m = GetParam().distance_m;
  s.angle_deg = GetParam().angle_deg;
  s.hole_rate = GetParam().hole_rate;
  s.frames = GetParam().frames;
  const Scene scene(s);
  VectorSource src(&scene);
  PanelParams p;
  const ExtractResult r = ExtractPanel(src, scene.in, p);
  ASSERT_TRUE(r.detection.found) << r.detection.why_not;
  ASSERT_EQ(r.metrics.status, "ok") << r.metrics.message;
  EXPECT_GE(IoU(r.region, scene.footprint), 0.85);
  const double zt = scene.TrueMedianDepth();
  EXPECT_NEAR(r.metrics.median_m, zt, QuantStep(zt, scene.in.fx) + 0.001 * zt);
  EXPECT_NEAR(r.metrics.hole_rate_pct, 100 * s.hole_rate, 1.0);
  const Eigen::Vector3d& c = scene.panel.center;
  EXPECT_NEAR(r.metrics.azimuth_deg, std::atan2(c.x(), c.z()) * 180 / M_PI, 0.5);
  EXPECT_NEAR(r.metrics.normal_tilt_deg, std::fabs(s.angle_deg), 2.0);
  EXPECT_NEAR(r.metrics.panel_width_m, 1.0, 0.1);
  EXPECT_NEAR(r.metrics.panel_height_m, 1.0, 0.1);
}

INSTANTIATE_TEST_SUITE_P(
    ArticleGrid, PanelAtTestPoint,
    ::testing::Values(Point{4, 0, 0.05, 20}, Point{4, 35, 0.35, 20}, Point{8, 10, 0.3, 20},
                      Point{12, 20, 0.75, 20}, Point{16, 0, 0.4, 20}, Point{16, 35, 0.99, 300}));

// A panel with 1 % valid pixels per frame is still found from 30 pooled frames.
TEST(PanelDetect, SparsePanelIsFoundFromPooledFrames) {
  SceneSpec s;
  s.distance_m = 16;
  s.angle_deg = 35;
  s.hole_rate = 0.99;
  s.frames = 30;
  const Scene scene(s);
  VectorSource src(&scene);
  const ExtractResult r = ExtractPanel(src, scene.in, PanelParams{});
  ASSERT_TRUE(r.detection.found) << r.detection.why_not;
  EXPECT_GE(IoU(r.region, scene.footprint), 0.85);
  EXPECT_NEAR(r.metrics.hole_rate_pct, 99.0, 1.0);
  EXPECT_EQ(r.passes, 1);  // the pooled frames are kept and measured: each read once
  EXPECT_EQ(src.rewinds, 0);
  EXPECT_EQ(r.frames_read, 30u);
  EXPECT_EQ(r.metrics.frames, 30);
}

// Without keeping the pooled frames, the recording is read again from the start, and the
// measurement is the same.
TEST(PanelDetect, ReadingTwiceMeasuresTheSame) {
  SceneSpec s;
  s.distance_m = 8;
  s.hole_rate = 0.9;
  s.frames = 40;  // more than detection_frames: the kept frames and the rest are both measured
  const Scene scene(s);
  VectorSource once(&scene), twice(&scene);
  PanelParams p;
  const ExtractResult a = ExtractPanel(once, scene.in, p);
  p.keep_detection_frames = false;
  const ExtractResult b = ExtractPanel(twice, scene.in, p);
  ASSERT_EQ(a.metrics.status, "ok") << a.metrics.message;
  ASSERT_EQ(b.metrics.status, "ok") << b.metrics.message;
  EXPECT_EQ(a.passes, 1);
  EXPECT_EQ(a.frames_read, 40u);
  EXPECT_EQ(b.passes, 2);
  EXPECT_EQ(b.frames_read, 70u);
  EXPECT_EQ(a.metrics.frames, 40);
  EXPECT_EQ(a.metrics.median_m, b.metrics.median_m);
  EXPECT_EQ(a.metrics.mean_m, b.metrics.mean_m);
  EXPECT_EQ(a.metrics.hole_rate_pct, b.metrics.hole_rate_pct);
  EXPECT_EQ(a.metrics.normal_tilt_deg, b.metrics.normal_tilt_deg);
}

// detection_frames = 0 pools every frame and measures in a second pass over the source.
TEST(PanelDetect, PoolingEveryFrameReadsTwice) {
  SceneSpec s;
  s.frames = 12;
  const Scene scene(s);
  VectorSource src(&scene);
  PanelParams p;
  p.detection_frames = 0;
  const ExtractResult r = ExtractPanel(src, scene.in, p);
  ASSERT_EQ(r.metrics.status, "ok") << r.metrics.message;
  EXPECT_EQ(r.passes, 2);
  EXPECT_EQ(r.frames_read, 24u);
  EXPECT_EQ(r.metrics.frames, 12);
}

// The clutter (a bigger wall, a small box) is seen but the panel is chosen.
TEST(PanelDetect, ClutterDoesNotWin) {
  SceneSpec s;
  s.distance_m = 12;
  s.angle_deg = 10;
  s.hole_rate = 0.5;
  s.clutter = true;
  const Scene scene(s);
  VectorSource src(&scene);
  const ExtractResult r = ExtractPanel(src, scene.in, PanelParams{});
  ASSERT_TRUE(r.detection.found) << r.detection.why_not;
  EXPECT_GE(r.detection.candidates.size(), 3u);
  EXPECT_GE(IoU(r.region, scene.footprint), 0.85);
}

// A scene without a panel gives no_panel and says why; a frame of the wrong size gives error.
TEST(PanelDetect, NoPanelAndBadFramesAreReported) {
  SceneSpec s;
  s.panel_size_m = 3.0;  // a wall, not the 1 × 1 m panel
  const Scene scene(s);
  VectorSource src(&scene);
  const ExtractResult r = ExtractPanel(src, scene.in, PanelParams{});
  EXPECT_EQ(r.metrics.status, "no_panel");
  EXPECT_FALSE(r.metrics.message.empty());
  camera::Intrinsics small = scene.in;
  small.width = 640;
  VectorSource src2(&scene);
  const ExtractResult bad = ExtractPanel(src2, small, PanelParams{});
  EXPECT_EQ(bad.metrics.status, "error");
  EXPECT_NE(bad.metrics.message.find("1280x720"), std::string::npos) << bad.metrics.message;
}

// The manual box over the true panel measures the same depth as the automatic region.
TEST(PanelExtractBox, BoxInsideThePanelAgreesWithAutomatic) {
  SceneSpec s;
  s.distance_m = 8;
  const Scene scene(s);
  VectorSource a(&scene), b(&scene);
  const ExtractResult ra = ExtractPanel(a, scene.in, PanelParams{});
  ASSERT_EQ(ra.metrics.status, "ok");
  const metrics::PanelRegion& reg = ra.region;
  const PixelBox box{reg.u_min + 3.0, reg.v_min + 3.0, reg.u_max - 2.0, reg.v_max - 2.0};
  const ExtractResult rb = ExtractPanel(b, scene.in, PanelParams{}, {}, box);
  ASSERT_EQ(rb.metrics.status, "ok") << rb.metrics.message;
  EXPECT_NEAR(rb.metrics.median_m, ra.metrics.median_m, QuantStep(8, scene.in.fx));
  EXPECT_NEAR(rb.metrics.azimuth_deg, ra.metrics.azimuth_deg, 0.5);
  EXPECT_NEAR(rb.metrics.normal_tilt_deg, ra.metrics.normal_tilt_deg, 1.0);
  EXPECT_EQ(rb.metrics.region_px, (reg.u_max - reg.u_min - 5.0) * (reg.v_max - reg.v_min - 5.0));
}

// A far panel seen through holes (one valid sample a pixel in the pooled frames, as sunset High
// Accuracy at 12 m) beside a strip of textured background taken in by the window (a sample every
// frame): the first plane counts each observed pixel once, so the strip's many samples do not
// turn it off the panel; the strip is left out and the panel kept.
TEST(DecidePanelPixels, ADenseBackgroundStripDoesNotPullASparsePanelsPlane) {
  const camera::Intrinsics in;  // 1280 × 720, f = 640 px
  metrics::PanelRegion region;
  region.width = in.width;
  region.height = in.height;
  std::vector<metrics::PooledPixel> pooled;
  const double units = 0.001, panel_z = 12.0, background_z = 20.0;
  int strip = 0, panel = 0;
  for (int v = 340; v < 380; ++v)
    for (int u = 600; u < 660; ++u) {
      region.pixels.push_back(static_cast<std::uint32_t>(v * in.width + u));
      const bool background = u >= 656;  // 4 of 60 columns
      metrics::PooledPixel p;
      if (background) {
        p.count = 30;
        p.sum_counts = 30 * static_cast<std::uint64_t>(background_z / units);
        ++strip;
      } else if ((u + 3 * v) % 4 == 0) {  // a quarter of the panel's pixels seen, once each
        p.count = 1;
        p.sum_counts = static_cast<std::uint64_t>(panel_z / units) + (u % 3) * 10;
        ++panel;
      }
      pooled.push_back(p);
    }
  region.u_min = 600, region.u_max = 659, region.v_min = 340, region.v_max = 379;
  metrics::PanelPixelParams params;
  const metrics::PanelPixels decided =
      metrics::DecidePanelPixels(in, region, pooled, units, nullptr, params);
  ASSERT_TRUE(decided.plane_ok);
  ASSERT_GT(strip * 30, 3 * panel);  // the strip holds most of the samples
  const double tilt_deg =
      std::acos(std::fabs(decided.plane.normal.normalized().z())) * 180.0 / M_PI;
  EXPECT_LT(tilt_deg, 2.0);
  EXPECT_NEAR(decided.plane.DepthOnRay(Eigen::Vector3d(-0.03, 0.0, 1.0)), panel_z, 0.1);
  EXPECT_EQ(decided.behind, strip);
  EXPECT_EQ(decided.on_plane, panel);
}

// The region is drawn row by row from the last row's ends; every pixel of the image tested on
// its own must give the same pixels: rectangles near and far, turned about every axis, partly
// outside the image, on a pinhole camera and on one with lens distortion.
TEST(RegionFromRectangle, EqualsTheTestOfEveryPixel) {
  std::mt19937 rng(20261124);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto in = [&](double a, double b) { return a + (b - a) * unit(rng); };
  camera::Intrinsics pinhole;
  pinhole.width = 320;
  pinhole.height = 180;
  pinhole.fx = pinhole.fy = 160.0;
  pinhole.ppx = 160.3;
  pinhole.ppy = 89.6;
  camera::Intrinsics lens = pinhole;
  lens.coeffs = {-0.05, 0.01, 0.001, -0.001, 0.0};
  int drawn = 0, cut = 0;
  for (const camera::Intrinsics& cam : {pinhole, lens}) {
    for (int trial = 0; trial < 300; ++trial) {
      metrics::PanelRectangle rect;
      const Eigen::Matrix3d turn =
          (Eigen::AngleAxisd(in(-1.2, 1.2), Eigen::Vector3d::UnitY()) *
           Eigen::AngleAxisd(in(-0.6, 0.6), Eigen::Vector3d::UnitX()) *
           Eigen::AngleAxisd(in(-0.8, 0.8), Eigen::Vector3d::UnitZ()))
              .toRotationMatrix();
      const double z = in(1.0, 20.0);
      rect.center_m = {in(-1.2, 1.2) * z, in(-0.7, 0.7) * z, z};
      rect.axis_width = turn * Eigen::Vector3d::UnitX();
      rect.axis_up = turn * -Eigen::Vector3d::UnitY();
      rect.plane.normal = turn * -Eigen::Vector3d::UnitZ();
      rect.plane.offset_m = -rect.plane.normal.dot(rect.center_m);
      rect.width_m = in(0.05, 3.0);
      rect.height_m = in(0.05, 3.0);
      const double margin = trial % 3 == 0 ? 0.0 : trial % 3 == 1 ? 0.5 : 2.0;
      const metrics::PanelRegion region = metrics::RegionFromRectangle(cam, rect, margin);
      if (region.outline_px.size() != 4) continue;
      const Eigen::Vector2d foot = metrics::PixelFootprint(cam, rect);
      const double half_w = 0.5 * rect.width_m - margin * foot.x();
      const double half_h = 0.5 * rect.height_m - margin * foot.y();
      std::vector<std::uint32_t> every;
      for (int v = 0; v < cam.height; ++v)
        for (int u = 0; u < cam.width; ++u) {
          const Eigen::Vector2d r = camera::PixelToNormalized(cam, {u, v});
          Eigen::Vector2d st;
          if (half_w > 0 && half_h > 0 && rect.PlaneCoordinates({r.x(), r.y(), 1.0}, &st) &&
              std::fabs(st.x()) <= half_w && std::fabs(st.y()) <= half_h)
            every.push_back(static_cast<std::uint32_t>(v * cam.width + u));
        }
      ASSERT_EQ(region.pixels, every) << "trial " << trial << " at " << z << " m";
      if (!every.empty()) ++drawn;
      for (const Eigen::Vector2d& c : region.outline_px)
        if (c.x() < 0 || c.y() < 0 || c.x() > cam.width - 1 || c.y() > cam.height - 1) {
          cut += !every.empty();
          break;
        }
    }
  }
  // The trials drew regions, some of them cut by the image's border.
  EXPECT_GT(drawn, 300);
  EXPECT_GT(cut, 100);
}

}  // namespace
}  // namespace depthbias::panel
