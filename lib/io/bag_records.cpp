#include "io/bag_records.h"

#include <ros/serialization.h>
#include <sensor_msgs/CameraInfo.h>
#include <std_msgs/Float32.h>
#include <std_msgs/Header.h>
#include <std_msgs/String.h>

#include <climits>
#include <cstdint>
#include <cstring>

namespace depthbias::io::bag_detail {

void ByteReader::Need(std::size_t count) const {
  if (count > size_ - pos_) {
    throw FormatError("needs " + std::to_string(count) + " bytes at offset " +
                      std::to_string(pos_) + " of a " + std::to_string(size_) + "-byte field");
  }
}

std::uint32_t ByteReader::U32() {
  Need(4);
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | data_[pos_ + i];
  pos_ += 4;
  return v;
}

std::uint64_t ByteReader::U64() {
  Need(8);
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | data_[pos_ + i];
  pos_ += 8;
  return v;
}

const std::uint8_t* ByteReader::Bytes(std::size_t count) {
  Need(count);
  const std::uint8_t* p = data_ + pos_;
  pos_ += count;
  return p;
}

RecordHeader::RecordHeader(const std::uint8_t* data, std::size_t size)
    : bytes_(reinterpret_cast<const char*>(data), size) {
  ByteReader r(data, size);
  while (r.remaining() > 0) {
    const std::uint32_t n = r.U32();
    const std::size_t at = r.pos();
    const char* f = reinterpret_cast<const char*>(r.Bytes(n));
    const std::string_view field(f, n);
    const std::size_t eq = field.find('=');
    if (eq == std::string_view::npos) throw FormatError("record header field without '='");
    fields_.push_back({at, eq, at + eq + 1, n - eq - 1});
  }
}

std::string_view RecordHeader::Field(std::string_view name) const {
  const std::string_view all(bytes_);
  for (const Span& f : fields_)
    if (all.substr(f.name_at, f.name_size) == name) return all.substr(f.value_at, f.value_size);
  throw FormatError("record header has no '" + std::string(name) + "' field");
}

bool RecordHeader::Has(std::string_view name) const {
  const std::string_view all(bytes_);
  for (const Span& f : fields_)
    if (all.substr(f.name_at, f.name_size) == name) return true;
  return false;
}

std::uint8_t RecordHeader::Op() const {
  const std::string_view v = Field("op");
  if (v.size() != 1) throw FormatError("record op field is not one byte");
  return static_cast<std::uint8_t>(v[0]);
}

std::uint32_t RecordHeader::U32(std::string_view name) const {
  const std::string_view v = Field(name);
  if (v.size() != 4) throw FormatError("record field '" + std::string(name) + "' is not 4 bytes");
  return ByteReader(reinterpret_cast<const std::uint8_t*>(v.data()), 4).U32();
}

std::uint64_t RecordHeader::U64(std::string_view name) const {
  const std::string_view v = Field(name);
  if (v.size() != 8) throw FormatError("record field '" + std::string(name) + "' is not 8 bytes");
  return ByteReader(reinterpret_cast<const std::uint8_t*>(v.data()), 8).U64();
}

std::string RecordHeader::Str(std::string_view name) const { return std::string(Field(name)); }

namespace {

namespace ser = ros::serialization;

// A roscpp_serialization input stream over serialized bytes; overruns throw FormatError.
ser::IStream Stream(const std::uint8_t* data, std::size_t size) {
  if (size > UINT32_MAX) throw FormatError("message of " + std::to_string(size) + " bytes");
  return ser::IStream(const_cast<std::uint8_t*>(data), static_cast<std::uint32_t>(size));
}

template <typename F>
auto Checked(const char* what, F&& decode) {
  try {
    return decode();
  } catch (const ser::StreamOverrunException&) {
    throw FormatError(std::string(what) + " ends before its fields do");
  }
}

double StampMs(const ros::Time& t) {
  return static_cast<double>(t.sec) * 1e3 + static_cast<double>(t.nsec) * 1e-6;
}

int ParseIndexedName(const std::string& s, const std::string& prefix) {
  if (s.compare(0, prefix.size(), prefix) != 0 || s.size() == prefix.size() ||
      s.size() > prefix.size() + 6)
    return -1;
  int v = 0;
  for (std::size_t i = prefix.size(); i < s.size(); ++i) {
    if (s[i] < '0' || s[i] > '9') return -1;
    v = v * 10 + (s[i] - '0');
  }
  return v;
}

}  // namespace

ImageView DecodeImage(const std::uint8_t* data, std::size_t size) {
  return Checked("image message", [&] {
    ser::IStream s = Stream(data, size);
    ImageView m;
    std_msgs::Header header;
    s.next(header);
    m.seq = header.seq;
    m.stamp_ms = StampMs(header.stamp);
    m.frame_id = header.frame_id;
    std::uint8_t big_endian = 0;
    s.next(m.height);
    s.next(m.width);
    s.next(m.encoding);
    s.next(big_endian);
    m.big_endian = big_endian != 0;
    s.next(m.step);
    s.next(m.data_size);
    m.data = s.advance(m.data_size);  // the pixels stay where they are
    // librealsense's extended header: the frame's depth units after the image data.
    if (m.frame_id == "1" && s.getLength() >= 4) {
      m.has_depth_units = true;
      s.next(m.depth_units);
    }
    return m;
  });
}

void DecodeStamp(const std::uint8_t* data, std::size_t size, std::uint32_t* seq,
                 double* stamp_ms) {
  Checked("message header", [&] {
    ser::IStream s = Stream(data, size);
    std_msgs::Header header;
    s.next(header);
    *seq = header.seq;
    *stamp_ms = StampMs(header.stamp);
    return 0;
  });
}

CameraInfoView DecodeCameraInfo(const std::uint8_t* data, std::size_t size) {
  return Checked("camera_info message", [&] {
    // roscpp_serialization sizes D before it checks the bytes are there: check first.
    ser::IStream peek = Stream(data, size);
    std_msgs::Header header;
    std::uint32_t u32 = 0;
    std::string model;
    peek.next(header);
    peek.next(u32);
    peek.next(u32);
    peek.next(model);
    peek.next(u32);
    if (u32 > peek.getLength() / 8)
      throw FormatError("camera_info claims " + std::to_string(u32) + " distortion coefficients");
    ser::IStream s = Stream(data, size);
    sensor_msgs::CameraInfo info;
    s.next(info);
    CameraInfoView m;
    m.height = info.height;
    m.width = info.width;
    m.distortion_model = info.distortion_model;
    m.d = info.D;
    for (int i = 0; i < 9; ++i) m.k[i] = info.K[i];
    return m;
  });
}

StreamInfoView DecodeStreamInfo(const std::uint8_t* data, std::size_t size) {
  return Checked("stream info message", [&] {
    ser::IStream s = Stream(data, size);
    StreamInfoView m;
    s.next(m.fps);
    s.next(m.encoding);
    return m;
  });
}

void DecodeKeyValue(const std::uint8_t* data, std::size_t size, std::string* key,
                    std::string* value) {
  Checked("key/value message", [&] {
    ser::IStream s = Stream(data, size);
    s.next(*key);
    s.next(*value);
    return 0;
  });
}

float DecodeFloat32(const std::uint8_t* data, std::size_t size) {
  return Checked("float32 message", [&] {
    ser::IStream s = Stream(data, size);
    std_msgs::Float32 m;
    s.next(m);
    return m.data;
  });
}

std::string DecodeString(const std::uint8_t* data, std::size_t size) {
  return Checked("string message", [&] {
    ser::IStream s = Stream(data, size);
    std_msgs::String m;
    s.next(m);
    return m.data;
  });
}

TopicParts ParseTopic(const std::string& topic) {
  TopicParts t;
  std::vector<std::string> parts;
  std::size_t start = 1;
  if (topic.empty() || topic[0] != '/') return t;
  while (start <= topic.size()) {
    const std::size_t slash = topic.find('/', start);
    const std::size_t end = slash == std::string::npos ? topic.size() : slash;
    parts.push_back(topic.substr(start, end - start));
    if (slash == std::string::npos) break;
    start = slash + 1;
  }
  if (parts.empty()) return t;
  t.device = ParseIndexedName(parts[0], "device_");
  if (t.device < 0 || parts.size() < 2) return t;
  t.sensor = ParseIndexedName(parts[1], "sensor_");
  if (t.sensor < 0 || parts.size() < 3) return t;
  std::size_t rest_from = 3;
  if (parts[2] == "option") {
    if (parts.size() < 4) return t;
    t.option = parts[3];
    rest_from = 4;
  } else {
    const std::size_t us = parts[2].rfind('_');
    const int index =
        (us == std::string::npos || us == 0) ? -1 : ParseIndexedName(parts[2].substr(us), "_");
    if (index < 0) {
      rest_from = 2;  // a sensor-level topic such as /device_0/sensor_0/info
    } else {
      t.stream_type = parts[2].substr(0, us);
      t.stream_index = index;
    }
  }
  for (std::size_t i = rest_from; i < parts.size(); ++i) {
    if (i > rest_from) t.rest += '/';
    t.rest += parts[i];
  }
  return t;
}

}  // namespace depthbias::io::bag_detail
