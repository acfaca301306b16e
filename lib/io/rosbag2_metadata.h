#pragma once
// A rosbag2 folder's metadata.yaml (as `ros2 bag record` writes it, rosbag2_storage's
// BagMetadata): key rosbag2_bagfile_information with version, storage_identifier ("mcap" or
// "sqlite3"), relative_file_paths, duration {nanoseconds}, starting_time
// {nanoseconds_since_epoch}, message_count, topics_with_message_count [{topic_metadata {name,
// type, serialization_format, ...}, message_count}], compression_format ("" or "zstd") and
// compression_mode ("", "FILE" or "MESSAGE"). Read with the project's YAML limits.

#include <cstdint>
#include <string>
#include <vector>

#include "io/rosbag2_storage.h"

namespace depthbias::io {

struct Rosbag2Metadata {
  int version = 0;
  std::string storage_identifier;
  std::vector<std::string> relative_file_paths;
  std::int64_t duration_ns = 0;
  std::int64_t starting_time_ns = 0;
  std::uint64_t message_count = 0;
  std::vector<Ros2Topic> topics;
  std::string compression_format;
  std::string compression_mode;
};

// Parses text (the file's contents). Throws IoError naming file (and what is wrong).
Rosbag2Metadata ParseRosbag2Metadata(const std::string& text, const std::string& file);
Rosbag2Metadata ReadRosbag2Metadata(const std::string& path);

}  // namespace depthbias::io
