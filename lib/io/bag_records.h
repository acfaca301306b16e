#pragma once
// Private to io. Two things rosbag_storage does not give the reader:
// - the ROS1 bag v2.0 record layout (http://wiki.ros.org/Bags/Format/2.0) read with bounds
//   checks, for the structural check made before a file is handed to rosbag::Bag and for reading
//   the frames before the damage of a bag rosbag cannot open (partial reads);
// - decoding of the messages a RealSense recording holds from their serialized bytes, with
//   roscpp_serialization, shared by the rosbag path and the partial path.
// Damaged input throws FormatError instead of reading past a buffer or allocating without bound.

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace depthbias::io::bag_detail {

struct FormatError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Record op codes.
constexpr std::uint8_t kOpMessage = 0x02;
constexpr std::uint8_t kOpBagHeader = 0x03;
constexpr std::uint8_t kOpIndexData = 0x04;
constexpr std::uint8_t kOpChunk = 0x05;
constexpr std::uint8_t kOpChunkInfo = 0x06;
constexpr std::uint8_t kOpConnection = 0x07;

constexpr char kMagic[] = "#ROSBAG V2.0\n";
constexpr std::size_t kMagicSize = 13;

// Little-endian reader over a byte range; every read checks the bounds.
class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  std::size_t remaining() const { return size_ - pos_; }
  std::size_t pos() const { return pos_; }

  std::uint32_t U32();
  std::uint64_t U64();
  const std::uint8_t* Bytes(std::size_t count);  // pointer to count bytes, then skips them

 private:
  void Need(std::size_t count) const;
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

// A record header: a sequence of (u32 length, "name=value") fields.
class RecordHeader {
 public:
  RecordHeader() = default;
  RecordHeader(const std::uint8_t* data, std::size_t size);  // throws FormatError

  bool Has(std::string_view name) const;
  std::uint8_t Op() const;
  std::uint32_t U32(std::string_view name) const;
  std::uint64_t U64(std::string_view name) const;
  std::string Str(std::string_view name) const;

 private:
  struct Span {
    std::size_t name_at, name_size, value_at, value_size;
  };
  std::string_view Field(std::string_view name) const;
  std::string bytes_;  // owned copy: the header outlives the buffer it was read from
  std::vector<Span> fields_;
};

// sensor_msgs/Image as librealsense writes it. When header.frame_id is "1" (librealsense's
// marker of its extended header), a float32 with the frame's depth units follows the data.
struct ImageView {
  std::uint32_t seq = 0;
  double stamp_ms = 0.0;
  std::string frame_id;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string encoding;
  bool big_endian = false;
  std::uint32_t step = 0;
  const std::uint8_t* data = nullptr;  // points into the serialized bytes
  std::uint32_t data_size = 0;
  bool has_depth_units = false;
  float depth_units = 0.0f;
};
ImageView DecodeImage(const std::uint8_t* data, std::size_t size);  // throws FormatError

// The std_msgs/Header part only: seq and stamp.
void DecodeStamp(const std::uint8_t* data, std::size_t size, std::uint32_t* seq, double* stamp_ms);

// sensor_msgs/CameraInfo fields the reader needs.
struct CameraInfoView {
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::string distortion_model;
  std::vector<double> d;
  double k[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
};
CameraInfoView DecodeCameraInfo(const std::uint8_t* data, std::size_t size);

// realsense_msgs/StreamInfo: fps, encoding, is_recommended.
struct StreamInfoView {
  std::uint32_t fps = 0;
  std::string encoding;
};
StreamInfoView DecodeStreamInfo(const std::uint8_t* data, std::size_t size);

// diagnostic_msgs/KeyValue (device and sensor info), std_msgs/Float32 (option values) and
// std_msgs/String (option descriptions).
void DecodeKeyValue(const std::uint8_t* data, std::size_t size, std::string* key,
                    std::string* value);
float DecodeFloat32(const std::uint8_t* data, std::size_t size);
std::string DecodeString(const std::uint8_t* data, std::size_t size);

// Parts of a RealSense topic /device_<d>/sensor_<s>/<Type>_<i>/<rest>, or of
// /device_<d>/sensor_<s>/option/<Name>/<rest>. Missing parts are -1 / empty.
struct TopicParts {
  int device = -1;
  int sensor = -1;
  std::string stream_type;  // "Depth", "Color", ... (empty for option topics)
  int stream_index = -1;
  std::string option;       // option name for option topics
  std::string rest;         // e.g. "image/data", "info/camera_info", "value"
};
TopicParts ParseTopic(const std::string& topic);

}  // namespace depthbias::io::bag_detail
