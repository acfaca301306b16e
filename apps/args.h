#pragma once
// The command line of an app, walked flag by flag. Mistakes throw std::invalid_argument with a
// one-line message naming the flag; numbers are checked whole ("2abc", "nan", "1e999" and
// out-of-range values are refused, never read as a prefix or clamped).

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

namespace depthbias::apps {

constexpr double kNoLimit = std::numeric_limits<double>::infinity();

// The number `text` (given for `flag`) holds: all of it a finite number in
// [min_value, max_value], a whole one if `whole`.
inline double FlagNumber(const std::string& flag, const std::string& text, bool whole,
                         double min_value, double max_value = kNoLimit) {
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v) || v < min_value ||
      v > max_value || (whole && v != std::floor(v))) {
    auto num = [](double x) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.10g", x);
      return std::string(buf);
    };
    const std::string range = std::isinf(min_value) && std::isinf(max_value) ? ""
                              : std::isinf(max_value) ? " >= " + num(min_value)
                                  : " in [" + num(min_value) + ", " + num(max_value) + "]";
    throw std::invalid_argument(flag + " '" + text + "' is not a " +
                                (whole ? "whole" : "finite") + " number" + range);
  }
  return v;
}

class Args {
 public:
  Args(int argc, char** argv) : argc_(argc), argv_(argv) {}

  // Moves to the next argument; false after the last.
  bool Next() {
    if (++i_ >= argc_) return false;
    flag_ = argv_[i_];
    return true;
  }
  const std::string& flag() const { return flag_; }
  bool IsHelp() const { return flag_ == "--help" || flag_ == "-h"; }

  // The flag's value: the argument after it.
  std::string Value() {
    if (i_ + 1 >= argc_) throw std::invalid_argument(flag_ + " needs a value");
    return argv_[++i_];
  }
  // The flag's value as a number (FlagNumber).
  double Number(bool whole, double min_value, double max_value = kNoLimit) {
    return FlagNumber(flag_, Value(), whole, min_value, max_value);
  }

 private:
  int argc_;
  char** argv_;
  int i_ = 0;
  std::string flag_;
};

}  // namespace depthbias::apps
