#include "io/bag_summary.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace depthbias::io {
namespace {

std::string Quote(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\r': out += "\\r"; break;
      case '\t': out += "\\t"; break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

std::string JsonNumber(double v) { return std::isfinite(v) ? FormatNumber(v) : "null"; }

std::string Get(const std::map<std::string, std::string>& m, const std::string& key) {
  const auto it = m.find(key);
  return it == m.end() ? std::string() : it->second;
}

}  // namespace

std::string FormatNumber(double value) {
  char buf[40];
  const bool is_float =
      std::isfinite(value) && static_cast<double>(static_cast<float>(value)) == value;
  // %g switches to an exponent when the integer part has more digits than the precision.
  const int integer_digits =
      std::isfinite(value) && std::fabs(value) >= 1.0
          ? static_cast<int>(std::floor(std::log10(std::fabs(value)))) + 1
          : 1;
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof buf, "%.*g", precision, value);
    const double back = std::strtod(buf, nullptr);
    if (is_float ? static_cast<float>(back) == static_cast<float>(value) : back == value) {
      if (precision < integer_digits && integer_digits <= 17)
        std::snprintf(buf, sizeof buf, "%.*g", integer_digits, value);
      break;
    }
  }
  return buf;
}

std::string BagSummaryText(const BagInfo& info) {
  std::ostringstream o;
  o << "file:        " << info.file << "\n";
  o << "compression: " << (info.compressed ? "yes (lz4/bz2 chunks)" : "none") << "\n";
  if (!info.indexed) o << "index:       missing (read by scanning the chunks)\n";
  o << "device:      " << Get(info.device, "Name") << ", serial "
    << Get(info.device, "Serial Number") << ", firmware "
    << Get(info.device, "Firmware Version") << "\n";
  o << "streams:\n";
  for (const StreamInfo& s : info.streams) {
    o << "  " << s.stream_type << "_" << s.stream_index << "  sensor " << s.sensor_index << "  "
      << (s.encoding.empty() ? "-" : s.encoding) << "  " << s.width << "x" << s.height << "  "
      << s.fps << " fps  " << s.messages << " msgs  " << s.topic << "\n";
  }
  const camera::Intrinsics& in = info.depth_intrinsics;
  o << "depth:       " << info.depth.topic << "\n";
  if (info.has_depth_intrinsics) {
    o << "  intrinsics:  " << in.width << "x" << in.height << "  fx " << FormatNumber(in.fx)
      << "  fy " << FormatNumber(in.fy) << "  ppx " << FormatNumber(in.ppx) << "  ppy "
      << FormatNumber(in.ppy) << "  " << camera::DistortionName(in.model) << " [";
    for (std::size_t i = 0; i < in.coeffs.size(); ++i)
      o << (i ? ", " : "") << FormatNumber(in.coeffs[i]);
    o << "]\n";
  } else {
    o << "  intrinsics:  not recorded\n";
  }
  o << "  depth units: " << FormatNumber(info.depth_units_m) << " m\n";
  o << "  frames:      " << info.depth_frames << "\n";
  o << "  timestamps:  first " << std::fixed;
  o.precision(3);
  o << info.first_timestamp_ms << " ms, last " << info.last_timestamp_ms << " ms ("
    << (info.last_timestamp_ms - info.first_timestamp_ms) / 1000.0 << " s)\n";
  o.unsetf(std::ios::fixed);
  o << "options:\n";
  for (const auto& [name, value] : info.options)
    o << "  " << name << " = " << FormatNumber(value) << "\n";
  o << "device info:\n";
  for (const auto& [key, value] : info.device) o << "  " << key << ": " << value << "\n";
  return o.str();
}

std::string BagSummaryJson(const BagInfo& info) {
  std::ostringstream o;
  const camera::Intrinsics& in = info.depth_intrinsics;
  o << "{\"file\":" << Quote(info.file)
    << ",\"compressed\":" << (info.compressed ? "true" : "false")
    << ",\"indexed\":" << (info.indexed ? "true" : "false") << ",\"streams\":[";
  for (std::size_t i = 0; i < info.streams.size(); ++i) {
    const StreamInfo& s = info.streams[i];
    o << (i ? "," : "") << "{\"topic\":" << Quote(s.topic) << ",\"sensor\":" << s.sensor_index
      << ",\"type\":" << Quote(s.stream_type) << ",\"index\":" << s.stream_index
      << ",\"encoding\":" << Quote(s.encoding) << ",\"width\":" << s.width
      << ",\"height\":" << s.height << ",\"fps\":" << s.fps << ",\"messages\":" << s.messages
      << "}";
  }
  o << "],\"depth\":{\"topic\":" << Quote(info.depth.topic) << ",\"intrinsics\":";
  if (info.has_depth_intrinsics) {
    o << "{\"width\":" << in.width << ",\"height\":" << in.height << ",\"fx\":" << JsonNumber(in.fx)
      << ",\"fy\":" << JsonNumber(in.fy) << ",\"ppx\":" << JsonNumber(in.ppx)
      << ",\"ppy\":" << JsonNumber(in.ppy)
      << ",\"model\":" << Quote(camera::DistortionName(in.model)) << ",\"coeffs\":[";
    for (std::size_t i = 0; i < in.coeffs.size(); ++i)
      o << (i ? "," : "") << JsonNumber(in.coeffs[i]);
    o << "]}";
  } else {
    o << "null";
  }
  o << ",\"depth_units\":" << JsonNumber(info.depth_units_m) << ",\"frames\":" << info.depth_frames
    << ",\"first_timestamp_ms\":" << JsonNumber(info.first_timestamp_ms)
    << ",\"last_timestamp_ms\":" << JsonNumber(info.last_timestamp_ms) << "},\"options\":{";
  bool first = true;
  for (const auto& [name, value] : info.options) {
    o << (first ? "" : ",") << Quote(name) << ":" << JsonNumber(value);
    first = false;
  }
  o << "},\"device\":{\"name\":" << Quote(Get(info.device, "Name"))
    << ",\"serial\":" << Quote(Get(info.device, "Serial Number"))
    << ",\"firmware\":" << Quote(Get(info.device, "Firmware Version")) << ",\"all\":{";
  first = true;
  for (const auto& [key, value] : info.device) {
    o << (first ? "" : ",") << Quote(key) << ":" << Quote(value);
    first = false;
  }
  o << "}}}";
  return o.str();
}

std::string BagErrorJson(const std::string& file, const std::string& error) {
  return "{\"file\":" + Quote(file) + ",\"error\":" + Quote(error) + "}";
}

}  // namespace depthbias::io
