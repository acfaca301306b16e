#pragma once
// Numbers in messages, as a person writes them: 6 significant digits, no trailing zeros
// ("1", "0.25", "1e-300", "nan"), never "1.000000". One helper for every module's messages
// (data files keep their own exact formats: io::CsvNumber round-trips a double).

#include <cstdio>
#include <string>

namespace depthbias::records {

inline std::string NumberText(double value) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", value);
  return buf;
}

// "1 x 1 m", "1280 x 720 px".
inline std::string SizeText(double width, double height, const std::string& unit) {
  return NumberText(width) + " x " + NumberText(height) + (unit.empty() ? "" : " " + unit);
}

// A byte count in the largest unit that keeps it at least 1: "512 B", "8.6 GB", "1.2 TB".
inline std::string BytesText(double bytes) {
  const char* units[] = {"B", "kB", "MB", "GB", "TB", "PB"};
  int u = 0;
  while (bytes >= 1000.0 && u < 5) {
    bytes /= 1000.0;
    ++u;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g %s", bytes, units[u]);
  return buf;
}

}  // namespace depthbias::records
