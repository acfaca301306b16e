#pragma once
// CDR encoding (little-endian plain CDR, as rmw writes it; see io/cdr.h) of the ROS 2 messages
// the MCAP writer records: a depth frame as sensor_msgs/msg/Image (16UC1, millimetres when the
// units are 0.001 m), intrinsics as sensor_msgs/msg/CameraInfo, and the RealSense wrapper's
// depth_module parameters as an rcl_interfaces/msg/ParameterEvent. Also the message definitions
// written as the MCAP schemas (encoding "ros2msg").

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "camera/intrinsics.h"
#include "records/depth_frame.h"

namespace depthbias::io::ros2 {

std::string EncodeImage(const records::DepthFrame& frame, std::int64_t stamp_ns,
                        const std::string& frame_id);
std::string EncodeCameraInfo(const camera::Intrinsics& in, std::int64_t stamp_ns,
                             const std::string& frame_id);
// Integer parameters, all as new_parameters of one event from node.
std::string EncodeParameterEvent(const std::string& node,
                                 const std::vector<std::pair<std::string, std::int64_t>>& params,
                                 std::int64_t stamp_ns);

// The .msg text of a type and the types it uses (ros2msg schema encoding: dependencies after
// a line of '=' and "MSG: package/Type").
std::string MessageDefinition(const std::string& type);

}  // namespace depthbias::io::ros2
