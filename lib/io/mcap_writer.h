#pragma once
// Writes a depth recording as a rosbag2 MCAP file (profile "ros2", CDR messages), the layout
// the RealSense ROS 2 wrapper and `ros2 bag record -s mcap` give: topics
// /camera/camera/depth/image_rect_raw (sensor_msgs/msg/Image, 16UC1),
// /camera/camera/depth/camera_info (one per frame) and /parameter_events (the wrapper's
// depth_module.visual_preset and depth_module.emitter_enabled, once at the start, when the
// config's options name them). Chunks uncompressed or zstd, one frame each, with message
// indexes, and a summary section (schemas, channels, statistics, chunk indexes) before the
// footer. Written to PATH.part and renamed, like BagWriter (same Finish / Commit contract).

#include <memory>
#include <string>

#include "io/bag.h"

namespace depthbias::io {

struct McapWriterConfig {
  BagWriterConfig bag;  // intrinsics, depth units (must be 0.001: 16UC1 is millimetres), fps,
                        // options (Visual_Preset, Emitter_Enabled)
  bool zstd = true;     // chunk compression: zstd, else none
  int zstd_level = 1;   // 1 to 19

  bool IsValid(std::string* why) const;
};

class McapWriter {
 public:
  McapWriter(const std::string& path, McapWriterConfig config);  // throws BagError
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  void Write(const records::DepthFrame& frame);  // throws BagError
  void Close();                                 // Finish() then Commit()
  void Finish();                                // summary and footer at PATH.part
  void Commit();                                // PATH.part → PATH

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace depthbias::io
