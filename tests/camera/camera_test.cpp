#include <gtest/gtest.h>

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

}  // namespace
}  // namespace depthbias::camera
