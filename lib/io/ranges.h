#pragma once
// The ranges numbers read from files must lie in: one set of rules for every reader (metrics
// CSV, manifest, weights YAML, bags), so that a value one reader refuses is refused by all.
// A number outside its range is a damaged or made-up input, never data to pass on: angle 90
// makes tan α infinite, a median of 0 m or -5 m is no depth, depth units of 0 are no scale.

#include <cmath>
#include <string>

#include "records/number_text.h"

namespace depthbias::io {

struct NumberRule {
  double min;
  double max;
  bool min_open;  // min itself excluded
  bool max_open;  // max itself excluded
  const char* unit;
  bool whole = false;  // a count

  bool Holds(double v) const {
    return std::isfinite(v) && (min_open ? v > min : v >= min) &&
           (max_open ? v < max : v <= max) && (!whole || v == std::floor(v));
  }
  // "(-90, 90) deg"
  std::string Interval() const {
    std::string s = std::string(min_open ? "(" : "[") + records::NumberText(min) + ", " +
                    records::NumberText(max) + (max_open ? ")" : "]");
    return *unit ? s + " " + unit : s;
  }
  // "90 is outside (-90, 90) deg"; "" when v holds.
  std::string Why(double v) const {
    if (Holds(v)) return "";
    if (!std::isfinite(v)) return records::NumberText(v) + " is not a finite number";
    if (whole && v != std::floor(v)) return records::NumberText(v) + " is not a whole number";
    return records::NumberText(v) + " is outside " + Interval();
  }
};

namespace rules {
constexpr double kInf = HUGE_VAL;
// Nominal distances and measured depths and ranges: positive, and below 1 km (a D455 reads to
// about 20 m; depth counts of 65535 at the coarsest units, 0.01 m, are 655 m).
constexpr NumberRule kDistanceM{0.0, 1000.0, true, false, "m"};
// Off-axis angles: tan α must be finite.
constexpr NumberRule kAngleDeg{-90.0, 90.0, true, true, "deg"};
// Off-axis angles a bias model may be evaluated at (model/domain.h): at 80° tan α ≈ 5.7
// multiplies every angle term beyond anything a fit has seen.
constexpr NumberRule kOffAxisDeg{-80.0, 80.0, true, true, "deg"};
// A standard deviation whose square (a variance) is still a finite number [m].
constexpr NumberRule kSigmaM{0.0, 1e150, false, false, "m"};
// Directions of a point in front of the camera.
constexpr NumberRule kDirectionDeg{-180.0, 180.0, false, false, "deg"};
constexpr NumberRule kTiltDeg{0.0, 180.0, false, false, "deg"};
constexpr NumberRule kPercent{0.0, 100.0, false, false, "%"};
constexpr NumberRule kNonNegative{0.0, kInf, false, true, ""};
constexpr NumberRule kCount{0.0, kInf, false, true, "", true};
constexpr NumberRule kPositiveCount{1.0, kInf, false, true, "", true};
// Depth units [m per count]: the D455 offers 1e-6 to 0.01 m; wider bounds leave room for other
// devices and float32 rounding, and still refuse 0, negative, NaN and absurd scales.
constexpr NumberRule kDepthUnitsM{1e-7, 0.1, false, false, "m"};
// A disparity noise σ_d [px]: positive (a margin of zero noise claims too much), and far below
// any disparity a stereo camera searches (the D455's is 0–95 px at 1280×720, 1/32 px steps).
constexpr NumberRule kDisparityNoisePx{0.0, 100.0, true, false, "px"};
// Standard deviations and errors in metres: zero or more, finite.
constexpr NumberRule kSpreadM{0.0, kInf, false, true, "m"};
}  // namespace rules

}  // namespace depthbias::io
