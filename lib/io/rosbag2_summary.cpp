// What bag_info prints for a rosbag2 recording: the layout of `ros2 bag info` (files, size,
// storage id, duration, start and end, messages, topic information), then what depthbias reads
// from it (compression, the depth topic and why, its frames and intrinsics, preset and emitter
// and where they came from) and what it does not hold.

#include <cstdio>
#include <ctime>

#include "io/bag_summary.h"
#include "io/rosbag2_source.h"

namespace depthbias::io {
namespace {

std::string Seconds(std::int64_t ns) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%lld.%09llds", static_cast<long long>(ns / 1000000000),
                static_cast<long long>(std::llabs(ns % 1000000000)));
  return buf;
}

std::string Date(std::int64_t ns) {
  const std::time_t t = static_cast<std::time_t>(ns / 1000000000);
  std::tm tm {};
  gmtime_r(&t, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, "%b %e %Y %H:%M:%S UTC", &tm);
  return std::string(buf) + " (" + Seconds(ns) + ")";
}

std::string Size(std::uint64_t bytes) {
  char buf[32];
  if (bytes >= (1ull << 30)) std::snprintf(buf, sizeof buf, "%.1f GiB", bytes / 1073741824.0);
  else if (bytes >= (1ull << 20)) std::snprintf(buf, sizeof buf, "%.1f MiB", bytes / 1048576.0);
  else std::snprintf(buf, sizeof buf, "%.1f KiB", bytes / 1024.0);
  return buf;
}

std::string Quote(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (c < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", c);
      out += b;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out + "\"";
}

std::string Settings(const BagInfo& info, const std::string& source) {
  if (source.empty()) return "not recorded (give them: the manifest's preset and emitter columns, or obstacle_detector's --preset and --emitter)";
  std::string s;
  const auto p = info.options.find("Visual_Preset");
  const auto e = info.options.find("Emitter_Enabled");
  if (p != info.options.end()) s += "Visual_Preset " + FormatNumber(p->second);
  if (e != info.options.end()) s += (s.empty() ? "" : ", ") + std::string("Emitter_Enabled ") +
                                    FormatNumber(e->second);
  return s + " (from " + source + ")";
}

}  // namespace

std::string Rosbag2SummaryText(const BagInfo& info, const Rosbag2Info& r2,
                               const std::string& settings, const std::string& damage) {
  std::string out;
  auto line = [&](const char* key, const std::string& value) {
    char buf[24];
    std::snprintf(buf, sizeof buf, "%-19s", key);
    out += buf + value + "\n";
  };
  std::string files;
  for (std::size_t i = 0; i < r2.files.size(); ++i)
    files += (i ? "\n                   " : "") + r2.files[i];
  line("Files:", files);
  line("Bag size:", Size(r2.bytes));
  line("Storage id:", r2.storage + (r2.has_metadata ? "" : " (no metadata.yaml)"));
  line("Compression:", r2.compression.empty() ? "none" : r2.compression);
  line("Duration:", Seconds(r2.end_ns - r2.start_ns));
  line("Start:", Date(r2.start_ns));
  line("End:", Date(r2.end_ns));
  std::uint64_t total = 0;
  for (const Ros2Topic& t : r2.topics) total += t.messages;
  line("Messages:", std::to_string(total));
  std::string topics;
  for (std::size_t i = 0; i < r2.topics.size(); ++i) {
    const Ros2Topic& t = r2.topics[i];
    topics += (i ? "\n                   " : "") + std::string("Topic: ") + t.name +
              " | Type: " + t.type + " | Count: " + std::to_string(t.messages) +
              " | Serialization Format: " + t.serialization_format;
  }
  line("Topic information:", topics);
  line("Indexed:", info.indexed ? "yes (summary section)" : "no (scanned)");
  line("Depth topic:", r2.depth_topic + " (" + r2.depth_topic_why + ")");
  line("Depth stream:", std::to_string(info.depth.width) + "x" +
                            std::to_string(info.depth.height) + " " + info.depth.encoding + ", " +
                            std::to_string(info.depth_frames) + " frames, units " +
                            FormatNumber(info.depth_units_m) + " m");
  if (info.has_depth_intrinsics) {
    const camera::Intrinsics& in = info.depth_intrinsics;
    char buf[200];
    std::snprintf(buf, sizeof buf, "%dx%d fx %.3f fy %.3f ppx %.3f ppy %.3f %s (%s)", in.width,
                  in.height, in.fx, in.fy, in.ppx, in.ppy,
                  camera::DistortionName(in.model).c_str(), r2.camera_info_topic.c_str());
    line("Intrinsics:", buf);
  }
  line("Preset/emitter:", Settings(info, settings));
  for (const std::string& m : r2.missing) line("Missing:", m);
  if (!damage.empty()) line("Damage:", damage);
  return out;
}

std::string Rosbag2SummaryJson(const BagInfo& info, const Rosbag2Info& r2,
                               const std::string& settings, const std::string& damage) {
  std::string out = "{\"file\":" + Quote(info.file) + ",\"format\":\"rosbag2\",\"storage\":" +
                    Quote(r2.storage) + ",\"compression\":" + Quote(r2.compression) +
                    ",\"indexed\":" + (info.indexed ? "true" : "false") +
                    ",\"bytes\":" + std::to_string(r2.bytes) +
                    ",\"duration_s\":" + FormatNumber((r2.end_ns - r2.start_ns) / 1e9) +
                    ",\"topics\":[";
  for (std::size_t i = 0; i < r2.topics.size(); ++i)
    out += std::string(i ? "," : "") + "{\"name\":" + Quote(r2.topics[i].name) + ",\"type\":" +
           Quote(r2.topics[i].type) + ",\"count\":" + std::to_string(r2.topics[i].messages) +
           "}";
  out += "],\"depth\":{\"topic\":" + Quote(r2.depth_topic) + ",\"encoding\":" +
         Quote(info.depth.encoding) + ",\"width\":" + std::to_string(info.depth.width) +
         ",\"height\":" + std::to_string(info.depth.height) +
         ",\"frames\":" + std::to_string(info.depth_frames);
  if (info.has_depth_intrinsics) {
    const camera::Intrinsics& in = info.depth_intrinsics;
    out += ",\"intrinsics\":{\"width\":" + std::to_string(in.width) +
           ",\"height\":" + std::to_string(in.height) + ",\"fx\":" + FormatNumber(in.fx) +
           ",\"fy\":" + FormatNumber(in.fy) + ",\"ppx\":" + FormatNumber(in.ppx) +
           ",\"ppy\":" + FormatNumber(in.ppy) + ",\"model\":" +
           Quote(camera::DistortionName(in.model)) + "}";
  }
  out += "},\"options\":{";
  bool first = true;
  for (const auto& kv : info.options) {
    out += (first ? "" : ",") + Quote(kv.first) + ":" + FormatNumber(kv.second);
    first = false;
  }
  out += "},\"settings_from\":" + Quote(settings.empty() ? "manifest" : settings) +
         ",\"missing\":[";
  for (std::size_t i = 0; i < r2.missing.size(); ++i)
    out += (i ? "," : "") + Quote(r2.missing[i]);
  out += "]";
  if (!damage.empty()) out += ",\"damage\":" + Quote(damage);
  return out + "}";
}

}  // namespace depthbias::io
