#pragma once
// One way to write a number for a person: at most `digits` significant digits, no trailing
// zeros ("1 x 1.2 m", not "1.000000 x 1.200000 m"); "nan" / "inf" as such.

#include <sstream>
#include <string>

namespace depthbias::common {

inline std::string Text(double value, int digits = 3) {
  std::ostringstream s;
  s.precision(digits);
  s << value;
  return s.str();
}

}  // namespace depthbias::common
