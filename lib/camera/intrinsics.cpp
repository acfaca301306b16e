#include "camera/intrinsics.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "records/number_text.h"

namespace depthbias::camera {
namespace {

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  s.erase(std::remove_if(s.begin(), s.end(),
                         [](char c) { return c == ' ' || c == '_' || c == '-'; }),
          s.end());
  return s;
}

}  // namespace

bool IsDistortionZero(const Intrinsics& in) {
  for (double c : in.coeffs)
    if (std::fabs(c) >= 1.1920929e-07) return false;
  return true;
}

std::string DistortionName(Distortion model) {
  switch (model) {
    case Distortion::kNone: return "None";
    case Distortion::kModifiedBrownConrady: return "Modified Brown Conrady";
    case Distortion::kInverseBrownConrady: return "Inverse Brown Conrady";
    case Distortion::kFTheta: return "Ftheta";
    case Distortion::kBrownConrady: return "Brown Conrady";
    case Distortion::kKannalaBrandt4: return "Kannala Brandt4";
  }
  return "unknown";
}

bool ParseDistortion(const std::string& name, Distortion* model) {
  const std::string n = Lower(name);
  if (n == "none" || n.empty()) {
    *model = Distortion::kNone;
  } else if (n == "modifiedbrownconrady") {
    *model = Distortion::kModifiedBrownConrady;
  } else if (n == "inversebrownconrady") {
    *model = Distortion::kInverseBrownConrady;
  } else if (n == "ftheta") {
    *model = Distortion::kFTheta;
  } else if (n == "brownconrady" || n == "plumbbob") {
    *model = Distortion::kBrownConrady;
  } else if (n == "kannalabrandt4" || n == "equidistant") {
    *model = Distortion::kKannalaBrandt4;
  } else {
    return false;
  }
  return true;
}

bool Intrinsics::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  using records::NumberText;
  if (width < 1 || height < 1 || width > kMaxImageSidePx || height > kMaxImageSidePx)
    return fail("image size " + std::to_string(width) + " x " + std::to_string(height) +
                " px is outside 1 to " + std::to_string(kMaxImageSidePx) + " px a side");
  if (!std::isfinite(fx) || !std::isfinite(fy) || !(fx > 0) || !(fy > 0))
    return fail("focal lengths " + records::SizeText(fx, fy, "px") +
                " must be positive and finite");
  // Plausible lenses only: a focal length between 1/100 and 100 times the image's larger side
  // (fields of view from about 0.6 to 178 degrees), square-ish pixels.
  const double side = std::max(width, height);
  for (double f : {fx, fy})
    if (f < kMinFocalPerSide * side || f > kMaxFocalPerSide * side)
      return fail("focal length " + NumberText(f) + " px is implausible for a " +
                  std::to_string(width) + " x " + std::to_string(height) + " px image (expected " +
                  NumberText(kMinFocalPerSide * side) + " to " +
                  NumberText(kMaxFocalPerSide * side) + " px)");
  if (fx > kMaxPixelAspect * fy || fy > kMaxPixelAspect * fx)
    return fail("focal lengths " + records::SizeText(fx, fy, "px") + " differ more than " +
                NumberText(kMaxPixelAspect) + " times");
  // The principal point within the image widened by its own size on every side.
  if (!std::isfinite(ppx) || !std::isfinite(ppy) || ppx < -width || ppx > 2.0 * width ||
      ppy < -height || ppy > 2.0 * height)
    return fail("principal point (" + NumberText(ppx) + ", " + NumberText(ppy) +
                ") px is implausible for a " + std::to_string(width) + " x " +
                std::to_string(height) + " px image");
  for (double c : coeffs)
    if (!std::isfinite(c) || std::fabs(c) > kMaxDistortionCoeff)
      return fail("distortion coefficient " + NumberText(c) + " is not a finite number within " +
                  "+-" + NumberText(kMaxDistortionCoeff));
  return true;
}

Eigen::Vector2d Project(const Intrinsics& in, const Eigen::Vector3d& point_m) {
  const auto& c = in.coeffs;
  double x = point_m.x() / point_m.z();
  double y = point_m.y() / point_m.z();
  if (in.model == Distortion::kModifiedBrownConrady ||
      in.model == Distortion::kInverseBrownConrady) {
    const double r2 = x * x + y * y;
    const double f = 1 + c[0] * r2 + c[1] * r2 * r2 + c[4] * r2 * r2 * r2;
    x *= f;
    y *= f;
    const double dx = x + 2 * c[2] * x * y + c[3] * (r2 + 2 * x * x);
    const double dy = y + 2 * c[3] * x * y + c[2] * (r2 + 2 * y * y);
    x = dx;
    y = dy;
  } else if (in.model == Distortion::kBrownConrady) {
    const double r2 = x * x + y * y;
    const double f = 1 + c[0] * r2 + c[1] * r2 * r2 + c[4] * r2 * r2 * r2;
    const double dx = x * f + 2 * c[2] * x * y + c[3] * (r2 + 2 * x * x);
    const double dy = y * f + 2 * c[3] * x * y + c[2] * (r2 + 2 * y * y);
    x = dx;
    y = dy;
  } else if (in.model == Distortion::kFTheta) {
    const double r = std::max(std::sqrt(x * x + y * y), 1.1920929e-07);
    const double rd = 1.0 / c[0] * std::atan(2 * r * std::tan(c[0] / 2.0));
    x *= rd / r;
    y *= rd / r;
  } else if (in.model == Distortion::kKannalaBrandt4) {
    const double r = std::max(std::sqrt(x * x + y * y), 1.1920929e-07);
    const double theta = std::atan(r);
    const double t2 = theta * theta;
    const double rd = theta * (1 + t2 * (c[0] + t2 * (c[1] + t2 * (c[2] + t2 * c[3]))));
    x *= rd / r;
    y *= rd / r;
  }
  return {x * in.fx + in.ppx, y * in.fy + in.ppy};
}

Eigen::Vector2d PixelToNormalized(const Intrinsics& in, const Eigen::Vector2d& pixel) {
  const auto& c = in.coeffs;
  double x = (pixel.x() - in.ppx) / in.fx;
  double y = (pixel.y() - in.ppy) / in.fy;
  const double x0 = x;
  const double y0 = y;
  // librealsense (src/rs.cpp) skips undistortion when every coefficient is below FLT_EPSILON,
  // which is what the D455 depth stream reports.
  if (IsDistortionZero(in)) return {x, y};
  // librealsense iterates 10 times (its comment: "10 iterations determined empirically").
  if (in.model == Distortion::kInverseBrownConrady) {
    for (int i = 0; i < 10; ++i) {
      const double r2 = x * x + y * y;
      const double icdist = 1.0 / (1 + ((c[4] * r2 + c[1]) * r2 + c[0]) * r2);
      const double xq = x / icdist;
      const double yq = y / icdist;
      const double delta_x = 2 * c[2] * xq * yq + c[3] * (r2 + 2 * xq * xq);
      const double delta_y = 2 * c[3] * xq * yq + c[2] * (r2 + 2 * yq * yq);
      x = (x0 - delta_x) * icdist;
      y = (y0 - delta_y) * icdist;
    }
  } else if (in.model == Distortion::kBrownConrady) {
    for (int i = 0; i < 10; ++i) {
      const double r2 = x * x + y * y;
      const double icdist = 1.0 / (1 + ((c[4] * r2 + c[1]) * r2 + c[0]) * r2);
      const double delta_x = 2 * c[2] * x * y + c[3] * (r2 + 2 * x * x);
      const double delta_y = 2 * c[3] * x * y + c[2] * (r2 + 2 * y * y);
      x = (x0 - delta_x) * icdist;
      y = (y0 - delta_y) * icdist;
    }
  } else if (in.model == Distortion::kKannalaBrandt4) {
    const double rd = std::max(std::sqrt(x * x + y * y), 1.1920929e-07);
    double theta = rd;
    double t2 = rd * rd;
    for (int i = 0; i < 4; ++i) {
      const double f =
          theta * (1 + t2 * (c[0] + t2 * (c[1] + t2 * (c[2] + t2 * c[3])))) - rd;
      if (std::fabs(f) < 1.1920929e-07) break;
      const double df =
          1 + t2 * (3 * c[0] + t2 * (5 * c[1] + t2 * (7 * c[2] + 9 * t2 * c[3])));
      theta -= f / df;
      t2 = theta * theta;
    }
    const double r = std::tan(theta);
    x *= r / rd;
    y *= r / rd;
  } else if (in.model == Distortion::kFTheta) {
    const double rd = std::max(std::sqrt(x * x + y * y), 1.1920929e-07);
    const double r = std::tan(c[0] * rd) / std::atan(2 * std::tan(c[0] / 2.0));
    x *= r / rd;
    y *= r / rd;
  }
  return {x, y};
}

Eigen::Vector3d Deproject(const Intrinsics& in, const Eigen::Vector2d& pixel, double depth_m) {
  const Eigen::Vector2d n = PixelToNormalized(in, pixel);
  return {depth_m * n.x(), depth_m * n.y(), depth_m};
}

Intrinsics D455::DepthIntrinsics() {
  Intrinsics in;
  in.width = 1280;
  in.height = 720;
  in.fx = in.fy = kFocalPx;
  in.ppx = 640.0;
  in.ppy = 360.0;
  in.model = Distortion::kBrownConrady;
  return in;
}

}  // namespace depthbias::camera
