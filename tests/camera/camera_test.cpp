#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "camera/disparity_noise.h"
#include "camera/intrinsics.h"

namespace depthbias::camera {
namespace {

TEST(Camera, DeprojectProjectRoundTripsWithoutDistortion) {
  const Intrinsics in = D455::DepthIntrinsics();
  const Eigen::Vector3d p = Deproject(in, {100.0, 650.0}, 7.5);
  EXPECT_DOUBLE_EQ(p.z(), 7.5);
  const Eigen::Vector2d px = Project(in, p);
  EXPECT_NEAR(px.x(), 100.0, 1e-9);
  EXPECT_NEAR(px.y(), 650.0, 1e-9);
}

TEST(Camera, DisparityDepthAreInverse) {
  const double d = DisparityFromDepth(4.0, 640.0, 0.095);
  EXPECT_NEAR(d, 15.2, 1e-12);
  EXPECT_NEAR(DepthFromDisparity(d, 640.0, 0.095), 4.0, 1e-12);
}

TEST(Camera, ModifiedBrownConradyDeprojectsAsUndistortedLikeLibrealsense) {
  Intrinsics in = D455::DepthIntrinsics();
  in.model = Distortion::kModifiedBrownConrady;
  in.coeffs = {-0.2, 0.05, 0.001, 0.001, 0.0};
  EXPECT_FALSE(IsDeprojectable(in));
  const Eigen::Vector3d p = Deproject(in, {0, 0}, 2.0);
  EXPECT_NEAR(p.x(), 2.0 * (0 - in.ppx) / in.fx, 1e-12);
}

TEST(Camera, ParsesDistortionNames) {
  Distortion m;
  ASSERT_TRUE(ParseDistortion("Brown Conrady", &m));
  EXPECT_EQ(m, Distortion::kBrownConrady);
  ASSERT_TRUE(ParseDistortion("Inverse Brown Conrady", &m));
  EXPECT_EQ(m, Distortion::kInverseBrownConrady);
  EXPECT_FALSE(ParseDistortion("fisheye-ish", &m));
}

// A frame's pixels added in one call (AddEach) count what adding them one by one counts: the
// number of pairs and σ_d (read from the bins), before and after further samples; NaN left
// out, beyond 4 px in the top bin, either sign. σ_d checked against values worked out here.
TEST(TemporalNoise, AddEachIsAddOneByOne) {
  std::vector<double> deltas;
  for (int i = 0; i < 5000; ++i) deltas.push_back(0.0137 * ((i * 7919) % 601 - 300));
  deltas.insert(deltas.end(), {NAN, 4.5, -9.0, 0.0, -0.0, 3.9995, 0.001, -0.001, INFINITY});
  TemporalNoise one, each;
  for (double d : deltas) one.Add(d);
  each.AddEach(deltas.size(), [&](std::size_t j) { return deltas[j]; });
  EXPECT_EQ(each.pairs(), one.pairs());
  EXPECT_EQ(each.pairs(), static_cast<long long>(deltas.size()) - 1);  // the NaN
  EXPECT_EQ(each.SigmaPx(), one.SigmaPx());
  // The bins themselves, through what each further sample does to σ_d.
  for (double extra : {0.0, 0.02, 0.5, 3.0}) {
    one.Add(extra);
    each.AddEach(1, [&](std::size_t) { return extra; });
    EXPECT_EQ(each.SigmaPx(), one.SigmaPx()) << extra;
  }
  // Worked out: 100 samples of ±0.0105 px (the bin [0.010, 0.011), centre 0.0105) and one of
  // 3 px beyond five robust scales: 101 pairs, σ_d = 0.0105/√2; a NaN adds nothing.
  TemporalNoise known;
  known.AddEach(102, [](std::size_t j) {
    return j == 100 ? 3.0 : j == 101 ? NAN : j % 2 ? 0.0105 : -0.0105;
  });
  EXPECT_EQ(known.pairs(), 101);
  EXPECT_NEAR(known.SigmaPx(), 0.0105 / std::sqrt(2.0), 1e-12);
}

}  // namespace
}  // namespace depthbias::camera
