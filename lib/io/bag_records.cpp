#include "io/bag_records.h"

#include <cstring>

namespace depthbias::io::bag_detail {

void ByteReader::Need(std::size_t count) const {
  if (count > size_ - pos_) {
    throw FormatError("needs " + std::to_string(count) + " bytes at offset " +
                      std::to_string(pos_) + " of a " + std::to_string(size_) + "-byte field");
  }
}

std::uint8_t ByteReader::U8() {
  Need(1);
  return data_[pos_++];
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

float ByteReader::F32() {
  const std::uint32_t bits = U32();
  float v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

double ByteReader::F64() {
  const std::uint64_t bits = U64();
  double v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

std::string ByteReader::String() {
  const std::uint32_t n = U32();
  const std::uint8_t* p = Bytes(n);
  return std::string(reinterpret_cast<const char*>(p), n);
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

// std_msgs/Header: seq, stamp (sec, nsec), frame_id.
void ReadHeader(ByteReader* r, std::uint32_t* seq, double* stamp_ms, std::string* frame_id) {
  *seq = r->U32();
  const std::uint32_t sec = r->U32();
  const std::uint32_t nsec = r->U32();
  *stamp_ms = StampMs(sec, nsec);
  const std::string id = r->String();
  if (frame_id) *frame_id = id;
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
  ByteReader r(data, size);
  ImageView m;
  ReadHeader(&r, &m.seq, &m.stamp_ms, &m.frame_id);
  m.height = r.U32();
  m.width = r.U32();
  m.encoding = r.String();
  m.big_endian = r.U8() != 0;
  m.step = r.U32();
  m.data_size = r.U32();
  m.data = r.Bytes(m.data_size);
  if (m.frame_id == "1" && r.remaining() >= 4) {
    m.has_depth_units = true;
    m.depth_units = r.F32();
  }
  return m;
}

void DecodeStamp(const std::uint8_t* data, std::size_t size, std::uint32_t* seq,
                 double* stamp_ms) {
  ByteReader r(data, size);
  ReadHeader(&r, seq, stamp_ms, nullptr);
}

CameraInfoView DecodeCameraInfo(const std::uint8_t* data, std::size_t size) {
  ByteReader r(data, size);
  CameraInfoView m;
  std::uint32_t seq;
  double stamp;
  ReadHeader(&r, &seq, &stamp, nullptr);
  m.height = r.U32();
  m.width = r.U32();
  m.distortion_model = r.String();
  const std::uint32_t nd = r.U32();
  if (nd > 64) throw FormatError("camera_info has " + std::to_string(nd) + " coefficients");
  for (std::uint32_t i = 0; i < nd; ++i) m.d.push_back(r.F64());
  for (double& k : m.k) k = r.F64();
  return m;
}

StreamInfoView DecodeStreamInfo(const std::uint8_t* data, std::size_t size) {
  ByteReader r(data, size);
  StreamInfoView m;
  m.fps = r.U32();
  m.encoding = r.String();
  return m;
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
