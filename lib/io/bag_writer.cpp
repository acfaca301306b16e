// Writes a depth-only bag in the layout of librealsense's recorder (file version 4), with
// rosbag_storage: static device, sensor, stream and option messages first, then one image and
// its metadata per frame. The image carries librealsense's extended header: frame_id "1" and the
// frame's depth units as a float32 after the pixels.

#include <geometry_msgs/Transform.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Float32.h>
#include <std_msgs/String.h>
#include <std_msgs/UInt32.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sys/stat.h>
#include <map>
#include <string>
#include <vector>

#include "io/bag.h"
#include "io/rosbag_guard.h"
#include "io/temp_files.h"

namespace depthbias::io {
namespace bag_detail {

// A message already serialized, with its type's name, md5 and definition: `bytes`, then the
// `span_size` bytes at `span` (borrowed: a frame's pixels go into the bag without a copy of
// their own), then `tail`.
struct RawMessage {
  std::string datatype;
  std::string md5;
  std::string definition;
  std::vector<std::uint8_t> bytes;
  const void* span = nullptr;
  std::size_t span_size = 0;
  std::vector<std::uint8_t> tail;

  std::size_t size() const { return bytes.size() + span_size + tail.size(); }
};

}  // namespace bag_detail
}  // namespace depthbias::io

namespace ros {
namespace message_traits {
template <>
struct MD5Sum<depthbias::io::bag_detail::RawMessage> {
  static const char* value(const depthbias::io::bag_detail::RawMessage& m) { return m.md5.c_str(); }
};
template <>
struct DataType<depthbias::io::bag_detail::RawMessage> {
  static const char* value(const depthbias::io::bag_detail::RawMessage& m) {
    return m.datatype.c_str();
  }
};
template <>
struct Definition<depthbias::io::bag_detail::RawMessage> {
  static const char* value(const depthbias::io::bag_detail::RawMessage& m) {
    return m.definition.c_str();
  }
};
}  // namespace message_traits
namespace serialization {
template <>
struct Serializer<depthbias::io::bag_detail::RawMessage> {
  template <typename Stream>
  inline static void write(Stream& stream, const depthbias::io::bag_detail::RawMessage& m) {
    if (!m.bytes.empty())
      std::memcpy(stream.advance(m.bytes.size()), m.bytes.data(), m.bytes.size());
    if (m.span_size) std::memcpy(stream.advance(m.span_size), m.span, m.span_size);
    if (!m.tail.empty()) std::memcpy(stream.advance(m.tail.size()), m.tail.data(), m.tail.size());
  }
  inline static uint32_t serializedLength(const depthbias::io::bag_detail::RawMessage& m) {
    return static_cast<uint32_t>(m.size());
  }
};
}  // namespace serialization
}  // namespace ros

namespace depthbias::io {
namespace {

using bag_detail::RawMessage;

// Message types librealsense's recorder uses that Debian ships no header for.
constexpr char kKeyValueMd5[] = "cf57fdc6617a881a88c16e768132149c";
constexpr char kKeyValueDefinition[] =
    "string key # what to label this value when viewing\n"
    "string value # a value to track over time\n";
constexpr char kStreamInfoMd5[] = "311d7e24eac31bb87271d041bf70ff7d";
constexpr char kStreamInfoDefinition[] =
    "# This message defines meta information for a stream\n"
    "# The stream type is expressed in the topic name\n\n"
    "uint32 fps        # The nominal streaming rate, defined in Hz\n"
    "string encoding   # Stream's data format\n"
    "bool is_recommended # Is this stream recommended by RealSense SDK\n";
constexpr std::uint32_t kFileVersion = 4;
constexpr std::uint64_t kFirstFrameNs = 1000000;

template <typename M>
RawMessage Typed() {
  RawMessage m;
  m.datatype = ros::message_traits::datatype<M>();
  m.md5 = ros::message_traits::md5sum<M>();
  m.definition = ros::message_traits::definition<M>();
  return m;
}

RawMessage Untyped(const char* datatype, const char* md5, const char* definition) {
  RawMessage m;
  m.datatype = datatype;
  m.md5 = md5;
  m.definition = definition;
  return m;
}

// Little-endian serialization into a RawMessage.
class Out {
 public:
  explicit Out(RawMessage* m) : b_(&m->bytes) {}
  explicit Out(std::vector<std::uint8_t>* bytes) : b_(bytes) {}
  Out& U8(std::uint8_t v) {
    b_->push_back(v);
    return *this;
  }
  Out& U32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) b_->push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    return *this;
  }
  Out& F32(float v) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, 4);
    return U32(bits);
  }
  Out& F64(double v) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, 8);
    for (int i = 0; i < 8; ++i) b_->push_back(static_cast<std::uint8_t>(bits >> (8 * i)));
    return *this;
  }
  Out& Str(const std::string& s) {
    U32(static_cast<std::uint32_t>(s.size()));
    b_->insert(b_->end(), s.begin(), s.end());
    return *this;
  }

 private:
  std::vector<std::uint8_t>* b_;
};

RawMessage KeyValue(const std::string& key, const std::string& value) {
  RawMessage m = Untyped("diagnostic_msgs/KeyValue", kKeyValueMd5, kKeyValueDefinition);
  Out(&m).Str(key).Str(value);
  return m;
}

std::string Spaced(std::string name) {
  for (char& c : name)
    if (c == '_') c = ' ';
  return name;
}

}  // namespace

struct BagWriter::Impl {
  std::string path;
  std::string temp_path;
  BagWriterConfig config;
  bag_detail::GuardedBag bag;
  bool open = false;
  bool finished = false;  // closed at temp_path, not yet renamed into place
  bool have_first = false;
  double first_ms = 0.0;
  std::uint64_t last_ns = 1;
  std::uint64_t frames = 0;
  const std::string prefix = "/device_0/sensor_0/";
  const std::string stream = "/device_0/sensor_0/Depth_0/";

  [[noreturn]] void Fail(const std::string& what) const {
    throw BagError(BagError::Kind::kWrite, path, what);
  }

  void Put(const std::string& topic, std::uint64_t time_ns, const RawMessage& m) {
    ros::Time t;
    t.fromNSec(std::max<std::uint64_t>(time_ns, 1));
    bag->write(topic, t, m);
  }

  void WriteStatic() {
    const std::uint64_t t0 = 1;  // ros::TIME_MIN: librealsense's time of static information
    RawMessage version = Typed<std_msgs::UInt32>();
    Out(&version).U32(kFileVersion);
    Put("/file_version", t0, version);
    for (const auto& [key, value] : config.device) Put("/device_0/info", t0, KeyValue(key, value));
    Put(prefix + "info", t0, KeyValue("Name", "Stereo Module"));

    RawMessage info = Untyped("realsense_msgs/StreamInfo", kStreamInfoMd5, kStreamInfoDefinition);
    Out(&info).U32(static_cast<std::uint32_t>(std::lround(config.fps))).Str("mono16").U8(1);
    Put(stream + "info", t0, info);

    const camera::Intrinsics& in = config.intrinsics;
    RawMessage ci = Typed<sensor_msgs::CameraInfo>();
    Out o(&ci);
    o.U32(0).U32(0).U32(0).Str("");  // header
    o.U32(static_cast<std::uint32_t>(in.height)).U32(static_cast<std::uint32_t>(in.width));
    o.Str(camera::DistortionName(in.model));
    o.U32(5);
    for (double c : in.coeffs) o.F64(c);
    const double k[9] = {in.fx, 0, in.ppx, 0, in.fy, in.ppy, 0, 0, 1};
    for (double v : k) o.F64(v);
    for (int i = 0; i < 9; ++i) o.F64(0.0);   // R
    for (int i = 0; i < 12; ++i) o.F64(0.0);  // P
    o.U32(0).U32(0);                          // binning
    o.U32(0).U32(0).U32(0).U32(0).U8(0);      // roi
    Put(stream + "info/camera_info", t0, ci);

    std::map<std::string, double> options = config.options;
    options["Depth_Units"] = config.depth_units_m;
    for (const auto& [name, value] : options) {
      RawMessage v = Typed<std_msgs::Float32>();
      Out(&v).F32(static_cast<float>(value));
      Put(prefix + "option/" + name + "/value", t0, v);
      RawMessage d = Typed<std_msgs::String>();
      Out(&d).Str(Spaced(name));
      Put(prefix + "option/" + name + "/description", t0, d);
    }

    RawMessage tf = Typed<geometry_msgs::Transform>();
    Out(&tf).F64(0).F64(0).F64(0).F64(0).F64(0).F64(0).F64(1);  // identity
    Put(stream + "tf/0", t0, tf);
  }
};

bool BagWriterConfig::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  std::string bad;
  if (!intrinsics.IsValid(&bad)) return fail("invalid intrinsics: " + bad);
  if (!(depth_units_m > 0) || !std::isfinite(depth_units_m))
    return fail("depth units must be positive");
  if (!(fps > 0) || !std::isfinite(fps)) return fail("fps must be positive");
  for (const auto& [name, value] : options) {
    if (name.empty() || name.find_first_of("/ ") != std::string::npos)
      return fail("option name '" + name + "' must be one word without '/'");
    if (!std::isfinite(value)) return fail("option " + name + " must be finite");
  }
  return true;
}

BagWriter::BagWriter(const std::string& path, BagWriterConfig config) : impl_(new Impl) {
  Impl& d = *impl_;
  d.path = path;
  d.config = std::move(config);
  std::string why;
  if (!d.config.IsValid(&why)) d.Fail(why);
  // Never renamed over a folder, a device or a pipe: refused before any frame is written.
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
    d.Fail(S_ISDIR(st.st_mode) ? "a folder has the bag's name"
                               : "exists and is not a regular file; a bag is never written over it");
  d.temp_path = path + ".part";
  try {
    RegisterTempFile(d.temp_path);
    d.bag.Open(d.temp_path, rosbag::bagmode::Write);
    d.open = true;
    if (d.config.compress_lz4) d.bag->setCompression(rosbag::compression::LZ4);
    d.WriteStatic();
  } catch (const std::exception& e) {
    d.open = false;
    try {
      d.bag.Close();
    } catch (const std::exception&) {
      // the first error is the one reported
    }
    std::remove(d.temp_path.c_str());
    UnregisterTempFile(d.temp_path);
    d.Fail(std::string("cannot write: ") + e.what());
  }
}

BagWriter::~BagWriter() {
  // Never closed or never committed: the recording was abandoned (an error unwound past it, or
  // a later recording of the run failed). Its partial file goes, so that no bag with frames
  // missing takes the final name and a run's bags are all or none.
  Impl& d = *impl_;
  if (!d.open && !d.finished) return;
  d.open = false;
  d.finished = false;
  try {
    d.bag.Close();
  } catch (const std::exception&) {
    // the file is removed below either way; a destructor must not throw
  }
  std::remove(d.temp_path.c_str());
  UnregisterTempFile(d.temp_path);
}

void BagWriter::Write(const records::DepthFrame& frame) {
  Impl& d = *impl_;
  if (!d.open) d.Fail("write after close");
  const camera::Intrinsics& in = d.config.intrinsics;
  if (frame.width != in.width || frame.height != in.height ||
      frame.counts.size() != static_cast<std::size_t>(frame.width) * frame.height)
    d.Fail("frame of " + std::to_string(frame.width) + " x " + std::to_string(frame.height) +
           " px does not match the stream's " + std::to_string(in.width) + " x " +
           std::to_string(in.height) + " px");
  if (!d.have_first) {
    d.first_ms = frame.timestamp_ms;
    d.have_first = true;
  }
  // Record time: time since the start of the recording, as librealsense's recorder stamps it.
  // librealsense's playback skips frames stamped at the time of the static information (1 ns),
  // so frames start 1 ms after it.
  const double elapsed_ns = std::max(0.0, (frame.timestamp_ms - d.first_ms) * 1e6);
  const std::uint64_t t =
      std::max<std::uint64_t>(d.last_ns, kFirstFrameNs + static_cast<std::uint64_t>(elapsed_ns));
  d.last_ns = t;

  RawMessage image = Typed<sensor_msgs::Image>();
  Out o(&image);
  // Device timestamp as ros::Time (seconds and nanoseconds), as librealsense stamps frames.
  const std::uint64_t stamp_ns =
      static_cast<std::uint64_t>(std::llround(std::max(0.0, frame.timestamp_ms) * 1e6));
  o.U32(static_cast<std::uint32_t>(frame.frame_number));
  o.U32(static_cast<std::uint32_t>(stamp_ns / 1000000000u));
  o.U32(static_cast<std::uint32_t>(stamp_ns % 1000000000u));
  o.Str("1");  // librealsense's marker: depth units follow the pixels
  o.U32(static_cast<std::uint32_t>(frame.height)).U32(static_cast<std::uint32_t>(frame.width));
  o.Str("mono16").U8(0).U32(static_cast<std::uint32_t>(frame.width * 2));
  o.U32(static_cast<std::uint32_t>(frame.counts.size() * 2));
  image.span = frame.counts.data();
  image.span_size = frame.counts.size() * 2;
  Out(&image.tail).F32(static_cast<float>(frame.depth_units_m));
  try {
    d.Put(d.stream + "image/data", t, image);
    d.Put(d.stream + "image/metadata", t, KeyValue("timestamp_domain", "Hardware Clock"));
  } catch (const std::exception& e) {
    d.Fail(std::string("cannot write frame: ") + e.what());
  }
  ++d.frames;
}

void BagWriter::Finish() {
  Impl& d = *impl_;
  if (!d.open) return;
  d.open = false;
  try {
    d.bag.Close();
  } catch (const std::exception& e) {
    std::remove(d.temp_path.c_str());
    UnregisterTempFile(d.temp_path);
    d.Fail(std::string("cannot close: ") + e.what());
  }
  d.finished = true;
}

void BagWriter::Commit() {
  Impl& d = *impl_;
  Finish();
  if (!d.finished) return;
  d.finished = false;
  if (std::rename(d.temp_path.c_str(), d.path.c_str()) != 0) {
    const std::string err = std::strerror(errno);
    std::remove(d.temp_path.c_str());
    UnregisterTempFile(d.temp_path);
    d.Fail("cannot rename the finished bag into place: " + err);
  }
  UnregisterTempFile(d.temp_path);
}

void BagWriter::Close() { Commit(); }

}  // namespace depthbias::io
