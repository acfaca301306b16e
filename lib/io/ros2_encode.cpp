#include "io/ros2_encode.h"

#include <cstring>

namespace depthbias::io::ros2 {
namespace {

class CdrWriter {
 public:
  CdrWriter() { out_.assign("\x00\x01\x00\x00", 4); }
  template <typename T>
  void Prim(T v) {
    while ((out_.size() - 4) % sizeof(T) != 0) out_.push_back('\0');
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    out_.append(b, sizeof(T));
  }
  void String(const std::string& s) {
    Prim<std::uint32_t>(static_cast<std::uint32_t>(s.size() + 1));
    out_.append(s);
    out_.push_back('\0');
  }
  void Bytes(const void* p, std::size_t n) {
    Prim<std::uint32_t>(static_cast<std::uint32_t>(n));
    out_.append(static_cast<const char*>(p), n);
  }
  void Header(std::int64_t stamp_ns, const std::string& frame_id) {
    Prim<std::int32_t>(static_cast<std::int32_t>(stamp_ns / 1000000000));
    Prim<std::uint32_t>(static_cast<std::uint32_t>(stamp_ns % 1000000000));
    String(frame_id);
  }
  std::string Take() { return std::move(out_); }

 private:
  std::string out_;
};

constexpr char kHeader[] =
    "builtin_interfaces/Time stamp\nstring frame_id\n"
    "================================================================================\n"
    "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n";

}  // namespace

std::string EncodeImage(const records::DepthFrame& frame, std::int64_t stamp_ns,
                        const std::string& frame_id) {
  CdrWriter w;
  w.Header(stamp_ns, frame_id);
  w.Prim<std::uint32_t>(static_cast<std::uint32_t>(frame.height));
  w.Prim<std::uint32_t>(static_cast<std::uint32_t>(frame.width));
  w.String("16UC1");
  w.Prim<std::uint8_t>(0);
  w.Prim<std::uint32_t>(static_cast<std::uint32_t>(frame.width * 2));
  w.Bytes(frame.counts.data(), frame.counts.size() * 2);
  return w.Take();
}

std::string EncodeCameraInfo(const camera::Intrinsics& in, std::int64_t stamp_ns,
                             const std::string& frame_id) {
  CdrWriter w;
  w.Header(stamp_ns, frame_id);
  w.Prim<std::uint32_t>(static_cast<std::uint32_t>(in.height));
  w.Prim<std::uint32_t>(static_cast<std::uint32_t>(in.width));
  const bool kb4 = in.model == camera::Distortion::kKannalaBrandt4;
  w.String(kb4 ? "equidistant" : "plumb_bob");
  const std::size_t nd = kb4 ? 4 : 5;
  w.Prim<std::uint32_t>(static_cast<std::uint32_t>(nd));
  for (std::size_t i = 0; i < nd; ++i) w.Prim<double>(in.coeffs[i]);
  const double k[9] = {in.fx, 0, in.ppx, 0, in.fy, in.ppy, 0, 0, 1};
  for (double v : k) w.Prim<double>(v);
  const double r[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (double v : r) w.Prim<double>(v);
  const double p[12] = {in.fx, 0, in.ppx, 0, 0, in.fy, in.ppy, 0, 0, 0, 1, 0};
  for (double v : p) w.Prim<double>(v);
  for (int i = 0; i < 6; ++i) w.Prim<std::uint32_t>(0);  // binning x, y; roi x, y, h, w
  w.Prim<std::uint8_t>(0);                                // roi do_rectify
  return w.Take();
}

std::string EncodeParameterEvent(const std::string& node,
                                 const std::vector<std::pair<std::string, std::int64_t>>& params,
                                 std::int64_t stamp_ns) {
  CdrWriter w;
  w.Prim<std::int32_t>(static_cast<std::int32_t>(stamp_ns / 1000000000));
  w.Prim<std::uint32_t>(static_cast<std::uint32_t>(stamp_ns % 1000000000));
  w.String(node);
  w.Prim<std::uint32_t>(static_cast<std::uint32_t>(params.size()));
  for (const auto& p : params) {
    w.String(p.first);
    w.Prim<std::uint8_t>(2);  // PARAMETER_INTEGER
    w.Prim<std::uint8_t>(0);
    w.Prim<std::int64_t>(p.second);
    w.Prim<double>(0.0);
    w.String("");
    for (int i = 0; i < 5; ++i) w.Prim<std::uint32_t>(0);  // the five arrays, empty
  }
  w.Prim<std::uint32_t>(0);  // changed_parameters
  w.Prim<std::uint32_t>(0);  // deleted_parameters
  return w.Take();
}

std::string MessageDefinition(const std::string& type) {
  const std::string sep =
      "================================================================================\n";
  if (type == "sensor_msgs/msg/Image")
    return std::string("std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
                       "uint8 is_bigendian\nuint32 step\nuint8[] data\n") +
           sep + "MSG: std_msgs/Header\n" + kHeader;
  if (type == "sensor_msgs/msg/CameraInfo")
    return std::string("std_msgs/Header header\nuint32 height\nuint32 width\n"
                       "string distortion_model\nfloat64[] d\nfloat64[9] k\nfloat64[9] r\n"
                       "float64[12] p\nuint32 binning_x\nuint32 binning_y\n"
                       "sensor_msgs/RegionOfInterest roi\n") +
           sep + "MSG: std_msgs/Header\n" + kHeader + sep +
           "MSG: sensor_msgs/RegionOfInterest\nuint32 x_offset\nuint32 y_offset\n"
           "uint32 height\nuint32 width\nbool do_rectify\n";
  if (type == "rcl_interfaces/msg/ParameterEvent")
    return "builtin_interfaces/Time stamp\nstring node\nrcl_interfaces/Parameter[] "
           "new_parameters\nrcl_interfaces/Parameter[] changed_parameters\n"
           "rcl_interfaces/Parameter[] deleted_parameters\n" +
           sep + "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n" + sep +
           "MSG: rcl_interfaces/Parameter\nstring name\nrcl_interfaces/ParameterValue value\n" +
           sep +
           "MSG: rcl_interfaces/ParameterValue\nuint8 type\nbool bool_value\n"
           "int64 integer_value\nfloat64 double_value\nstring string_value\n"
           "byte[] byte_array_value\nbool[] bool_array_value\nint64[] integer_array_value\n"
           "float64[] double_array_value\nstring[] string_array_value\n";
  return "";
}

}  // namespace depthbias::io::ros2
