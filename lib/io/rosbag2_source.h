#pragma once
// A rosbag2 recording (a folder with metadata.yaml, a bare .mcap or a bare .db3) as a
// RecordingSource: its depth topic's sensor_msgs/msg/Image frames, its camera_info as the depth
// intrinsics, and the RealSense wrapper's depth_module parameters (from
// rcl_interfaces/msg/ParameterEvent messages, when recorded) as the depth sensor's options.

#include <memory>
#include <string>
#include <vector>

#include "io/recording.h"
#include "io/rosbag2_storage.h"

namespace depthbias::io {

// What a ROS 2 recording holds beyond BagInfo, for bag_info.
struct Rosbag2Info {
  std::vector<std::string> files;  // storage files read
  std::uint64_t bytes = 0;         // their total size
  std::string storage;             // "mcap" / "sqlite3"
  std::string compression;         // chunk compressions
  bool has_metadata = false;       // read from a folder's metadata.yaml
  std::vector<Ros2Topic> topics;
  std::string depth_topic, camera_info_topic, parameter_topic;
  std::string depth_topic_why;     // how the depth topic was chosen
  std::int64_t start_ns = 0, end_ns = 0;
  std::vector<std::string> missing;  // what the recording does not hold
};

// The wrapper's depth topics, best first (ros2 launch realsense2_camera rs_launch.py: namespace
// and name both "camera" since wrapper 4.54, one "camera" before; aligned depth when
// align_depth.enable is set).
extern const char* const kWrapperDepthTopics[4];

std::unique_ptr<RecordingSource> OpenRosbag2(const std::string& path, RecordingFormat format,
                                             const RecordingOptions& options);

// For bag_info: the extra information of a source OpenRosbag2 made (nullptr for others).
const Rosbag2Info* Rosbag2InfoOf(const RecordingSource& source);

}  // namespace depthbias::io
