#pragma once
// D455 camera model: intrinsics, extrinsics, projection and deprojection exactly as librealsense
// computes them (include/librealsense2/rsutil.h, rs2_project_point_to_pixel and
// rs2_deproject_pixel_to_point), and the stereo relation between disparity and depth.

#include <array>
#include <string>

#include <Eigen/Core>

namespace depthbias::camera {

// Same order and values as librealsense's rs2_distortion.
enum class Distortion {
  kNone = 0,
  kModifiedBrownConrady = 1,
  kInverseBrownConrady = 2,
  kFTheta = 3,
  kBrownConrady = 4,
  kKannalaBrandt4 = 5,
};

// Name as librealsense prints it ("Brown Conrady", "Inverse Brown Conrady", ...).
std::string DistortionName(Distortion model);
// Parses librealsense's names and the ROS CameraInfo names RealSense bags use
// ("Brown Conrady", "plumb_bob", ...). Returns false for an unknown name.
bool ParseDistortion(const std::string& name, Distortion* model);

// Pinhole intrinsics of one stream, as rs2_intrinsics holds them.
struct Intrinsics {
  int width = 1280;   // [px]
  int height = 720;   // [px]
  double fx = 640.0;  // focal length [px]
  double fy = 640.0;  // focal length [px]
  double ppx = 640.0; // principal point [px], pixel centres at integer coordinates
  double ppy = 360.0; // principal point [px]
  Distortion model = Distortion::kBrownConrady;
  std::array<double, 5> coeffs{{0, 0, 0, 0, 0}};  // k1, k2, p1, p2, k3

  // Plausibility, checked wherever intrinsics come in (bag reader, sensor YAML, writer, panel
  // extraction): sides of 1 to kMaxImageSidePx, finite focal lengths of kMinFocalPerSide to
  // kMaxFocalPerSide times the larger side with fx/fy within kMaxPixelAspect, the principal
  // point within the image widened by its size on each side, |coefficients| <= 100. A camera
  // outside these bounds is a damaged or made-up record (fx = 1e-300 made PCL's clustering
  // crash), never a lens.
  bool IsValid(std::string* why) const;

  static constexpr int kMaxImageSidePx = 65535;
  static constexpr double kMinFocalPerSide = 0.01;
  static constexpr double kMaxFocalPerSide = 100.0;
  static constexpr double kMaxPixelAspect = 4.0;
  static constexpr double kMaxDistortionCoeff = 100.0;
};

// Rigid transform from one stream's frame to another's, as rs2_extrinsics holds it.
struct Extrinsics {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation_m = Eigen::Vector3d::Zero();

  Eigen::Vector3d Apply(const Eigen::Vector3d& p) const { return rotation * p + translation_m; }
};

// True when every coefficient is below FLT_EPSILON in magnitude (librealsense then treats the
// stream as undistorted).
bool IsDistortionZero(const Intrinsics& intrinsics);

// rs2_project_point_to_pixel: camera-frame point [m] → pixel [px].
Eigen::Vector2d Project(const Intrinsics& intrinsics, const Eigen::Vector3d& point_m);

// rs2_deproject_pixel_to_point: pixel [px] and depth Z [m] → camera-frame point [m].
// MODIFIED_BROWN_CONRADY has no inverse: librealsense asserts in debug builds and, in the release
// builds users run, deprojects it as undistorted; this does the same (see IsDeprojectable).
Eigen::Vector3d Deproject(const Intrinsics& intrinsics, const Eigen::Vector2d& pixel,
                          double depth_m);

// False for MODIFIED_BROWN_CONRADY (distortion applied on projection, no closed-form inverse).
inline bool IsDeprojectable(const Intrinsics& intrinsics) {
  return intrinsics.model != Distortion::kModifiedBrownConrady;
}

// Normalized ray (x/z, y/z) of a pixel: Deproject at Z = 1 without the z component.
Eigen::Vector2d PixelToNormalized(const Intrinsics& intrinsics, const Eigen::Vector2d& pixel);

// d = f·B / Z, with f [px], B [m], Z [m] → d [px].
inline double DisparityFromDepth(double depth_m, double focal_px, double baseline_m) {
  return focal_px * baseline_m / depth_m;
}
// Z = f·B / d.
inline double DepthFromDisparity(double disparity_px, double focal_px, double baseline_m) {
  return focal_px * baseline_m / disparity_px;
}

// Nominal D455 depth stream at 1280×720 (datasheet: baseline 95 mm, depth FOV 87°×58°).
struct D455 {
  static constexpr double kBaselineM = 0.095;
  static constexpr double kFocalPx = 640.0;  // approximate depth fx at 1280×720
  static constexpr double kSubpixelStepPx = 1.0 / 32.0;
  static Intrinsics DepthIntrinsics();
};

}  // namespace depthbias::camera
