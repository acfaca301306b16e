#include "model/domain.h"

#include <cmath>

#include "records/number_text.h"

namespace depthbias::model {

std::string OutsideDomain(double depth_m, double angle_deg) {
  if (!std::isfinite(depth_m)) return "median " + records::NumberText(depth_m) + " is no depth";
  if (!(depth_m >= kMinDepthM)) {
    return "median " + records::NumberText(depth_m) +
           " m is nearer than the camera's minimum range " + records::NumberText(kMinDepthM) +
           " m";
  }
  if (!(std::abs(angle_deg) < kMaxAngleDeg)) {
    return "angle " + records::NumberText(angle_deg) + " deg is at or beyond " +
           records::NumberText(kMaxAngleDeg) + " deg off axis";
  }
  return "";
}

}  // namespace depthbias::model
