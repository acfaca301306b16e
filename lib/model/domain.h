#pragma once
// Where a bias model has a physical meaning. A reading outside it is refused before anything is
// computed (the tools) or gets no prediction (NaN, the library): a median nearer than the camera
// can measure, or an off-axis angle whose tangent makes every angle term explode, is a damaged
// input, not a reading to correct. The model is even in the off-axis angle: it takes the signed
// angle and applies |α| itself, so −20° and 20° are corrected alike.

#include <string>

namespace depthbias::model {

// Nearest depth a reading may have [m]. Intel RealSense D400 series datasheet: the D455's
// Min-Z is about 0.52 m at 1280×720 and less at lower resolutions; 0.4 m keeps those.
constexpr double kMinDepthM = 0.4;
// Off-axis angles |α| at or beyond this are refused [deg]: the D455's depth field of view
// (87° × 58°, datasheet) reaches about 48° off axis in its corners, and tan 80° ≈ 5.7 already
// multiplies every angle term of a form beyond anything a fit has seen.
constexpr double kMaxAngleDeg = 80.0;
// Weights are checked over the readings a D455 gives: depths up to this [m] (the detector's
// default far limit, where σ_Z already passes 1 m) ...
constexpr double kCheckMaxDepthM = 20.0;
// ... and off-axis angles up to this [deg] (the corner of the depth field of view).
constexpr double kCheckMaxAngleDeg = 50.0;

// "" when (depth, angle) is a reading the model may correct, else why not, e.g.
// "median 0.1 m is nearer than the camera's minimum range 0.4 m".
std::string OutsideDomain(double depth_m, double angle_deg);

}  // namespace depthbias::model
