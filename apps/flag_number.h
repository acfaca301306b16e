#pragma once
// The number a command-line flag's value holds, checked whole: "2abc", "nan", "1e999" and
// out-of-range values are refused, never read as a prefix or clamped.

#include <cmath>
#include <limits>
#include <string>

namespace depthbias::apps {

// True, with *value set, when all of text is a finite number in [min_value, max_value], and a
// whole one if `whole`.
inline bool ParseFlagNumber(const std::string& text, bool whole, double min_value,
                            double max_value, double* value) {
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    return false;
  }
  if (used != text.size() || !std::isfinite(v) || v < min_value || v > max_value ||
      (whole && v != std::floor(v)))
    return false;
  *value = v;
  return true;
}

constexpr double kNoLimit = std::numeric_limits<double>::infinity();

}  // namespace depthbias::apps
