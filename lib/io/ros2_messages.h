#pragma once
// The ROS 2 messages a depth recording needs, decoded from CDR (io/cdr.h) with the field order
// of their .msg definitions (ros2/common_interfaces, ros2/rcl_interfaces):
//   sensor_msgs/msg/Image: std_msgs/Header header, uint32 height, uint32 width, string encoding,
//     uint8 is_bigendian, uint32 step, uint8[] data
//   sensor_msgs/msg/CameraInfo: header, uint32 height, uint32 width, string distortion_model,
//     float64[] d, float64[9] k, float64[9] r, float64[12] p, uint32 binning_x, binning_y, roi
//   rcl_interfaces/msg/ParameterEvent: builtin_interfaces/Time stamp, string node,
//     Parameter[] new_parameters, changed_parameters, deleted_parameters
// and their mapping to depthbias's records: a depth image to a DepthFrame, a CameraInfo to the
// camera module's Intrinsics. Every decoder returns false with a one-line reason.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "camera/intrinsics.h"
#include "records/depth_frame.h"

namespace depthbias::io::ros2 {

constexpr const char* kImageType = "sensor_msgs/msg/Image";
constexpr const char* kCameraInfoType = "sensor_msgs/msg/CameraInfo";
constexpr const char* kParameterEventType = "rcl_interfaces/msg/ParameterEvent";

// The scale of a 16UC1 depth image from the RealSense wrapper: its counts are the camera's own
// (the wrapper copies Z16 frames as they are), whose unit the D455 holds as the float32 0.001f
// (1.0000000475e-3 m). A ROS 1 bag records that same float, so both forms of one recording
// measure alike to the last digit.
constexpr double kDepthUnitsM = static_cast<double>(0.001f);

struct Image {
  std::int64_t stamp_ns = 0;
  std::string frame_id;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string encoding;
  std::uint8_t is_bigendian = 0;
  std::uint32_t step = 0;
  const std::uint8_t* data = nullptr;  // into the message's bytes
  std::size_t size = 0;
};

struct CameraInfo {
  std::int64_t stamp_ns = 0;
  std::string frame_id;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string distortion_model;
  std::vector<double> d;
  std::array<double, 9> k{};
  std::array<double, 9> r{};
  std::array<double, 12> p{};
};

// One rcl_interfaces/msg/Parameter; type as ParameterType (1 bool, 2 integer, 3 double,
// 4 string, 5 to 9 arrays).
struct Parameter {
  std::string name;
  std::uint8_t type = 0;
  bool bool_value = false;
  std::int64_t integer_value = 0;
  double double_value = 0.0;
  std::string string_value;
};

bool DecodeImage(const std::uint8_t* data, std::size_t size, Image* out, std::string* why);
bool DecodeCameraInfo(const std::uint8_t* data, std::size_t size, CameraInfo* out,
                      std::string* why);
// The new and changed parameters of one event, with the node that published it.
bool DecodeParameterEvent(const std::uint8_t* data, std::size_t size, std::string* node,
                          std::vector<Parameter>* out, std::string* why);

// A depth image as a DepthFrame: 16UC1 and mono16 counts as they are, at depth_units_m (the
// RealSense ROS 2 wrapper publishes millimetres); 32FC1 metres rounded to counts of
// kDepthUnitsM (NaN, infinite, zero and negative depths are no depth; beyond 65.535 m too).
// width × height is checked against the bytes the image holds before anything is allocated.
bool ImageToDepthFrame(const Image& image, double depth_units_m, records::DepthFrame* out,
                       std::string* why);
bool IsDepthEncoding(const std::string& encoding);

// CameraInfo → Intrinsics: fx = K[0], fy = K[4], ppx = K[2], ppy = K[5]; plumb_bob (k1, k2, p1,
// p2, k3) → Brown Conrady; rational_polynomial (k1, k2, p1, p2, k3, k4, k5, k6) → Brown Conrady
// when k4..k6 are zero (the camera module has no rational model; refused otherwise);
// equidistant (k1..k4) → Kannala Brandt4. Checked with Intrinsics::IsValid.
bool CameraInfoToIntrinsics(const CameraInfo& info, camera::Intrinsics* out, std::string* why);

}  // namespace depthbias::io::ros2
