// Streaming reader of RealSense ROS1 bags, on rosbag_storage.
//
// The normal path: rosbag::Bag opens the bag and reads its index; one rosbag::View over the
// metadata topics gives the device and sensor info, options, stream info and camera_info, and
// one over the depth topic gives the frames one at a time. Messages are decoded from their
// serialized bytes with roscpp_serialization (bag_records.h): metadata from
// MessageInstance::write(), depth frames in place in rosbag's chunk buffer through
// MessageInstance::instantiate() (no sensor_msgs::Image copy of the pixels). The decoder reads
// the serialized message to its end, so it also gets the depth units librealsense appends after
// the image data. rosbag keeps a small index entry per message and one chunk at a time, so
// memory stays flat however long the recording.
//
// rosbag trusts the file: a damaged size field makes it allocate or read without bound. So
// before a file is handed to rosbag, a structural check walks its records without
// decompressing anything (record and chunk headers, the index, the per-chunk index data and,
// in uncompressed chunks, the record of every indexed message). Errors rosbag raises while
// reading (e.g. an LZ4 chunk whose data fails roslz4's checks) become BagError too. The check
// does not look inside compressed chunks: there it only knows that each indexed message starts
// inside its chunk, and rosbag trusts the record it finds there (an index damaged to point into
// the middle of a message in an LZ4 chunk can make rosbag read past its chunk buffer).
//
// rosbag refuses a bag without its index (cut short, never closed) and one that fails the
// check. With ReadOptions::allow_partial such a bag is read by scanning its chunks in order
// with the same record reader, up to the damage.
//
// BagReader::Impl (bag_reader_impl.h) is defined in three files: this one opens the bag and
// holds what both paths share, bag_reader_records.cpp the structural check and the partial path,
// bag_reader_rosbag.cpp the rosbag path.

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <tuple>
#include <utility>

#include "io/bag.h"
#include "io/bag_reader_impl.h"
#include "io/bag_records.h"
#include "io/ranges.h"

namespace depthbias::io {
namespace {

using namespace bag_detail;

bool IsDepthEncoding(const std::string& e) { return e == "mono16" || e == "16UC1"; }

}  // namespace

BagError::BagError(Kind kind, const std::string& file, const std::string& what)
    : std::runtime_error(OneLine(file + ": " + what)), kind_(kind), file_(file) {}

BagReader::Impl::~Impl() {
  frames.reset();
  bag.reset();
  if (fd >= 0) ::close(fd);
}

void BagReader::Impl::Open() {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT || errno == ENOTDIR) Fail(BagError::Kind::kNotFound, "no such file");
    Fail(BagError::Kind::kNotFound, std::string("cannot access: ") + std::strerror(errno));
  }
  if (S_ISDIR(st.st_mode)) Fail(BagError::Kind::kNotAFile, "is a directory, not a bag file");
  if (!S_ISREG(st.st_mode)) Fail(BagError::Kind::kNotAFile, "is not a regular file");
  file_size = static_cast<std::uint64_t>(st.st_size);
  if (file_size == 0) Fail(BagError::Kind::kEmpty, "is empty (0 bytes)");
  fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    Fail(BagError::Kind::kNotFound, std::string("cannot open: ") + std::strerror(errno));

  char magic[kMagicSize] = {};
  const std::size_t head =
      static_cast<std::size_t>(std::min<std::uint64_t>(file_size, kMagicSize));
  ReadAt(0, head, reinterpret_cast<std::uint8_t*>(magic));
  if (head < kMagicSize || std::memcmp(magic, kMagic, kMagicSize) != 0) {
    if (head >= 9 && std::memcmp(magic, "#ROSBAG V", 9) == 0)
      Fail(BagError::Kind::kNotABag, "ROS bag format '" +
                                         OneLine(std::string(magic, head - 1)).substr(1) +
                                         "' is not supported (RealSense bags are V2.0)");
    Fail(BagError::Kind::kNotABag, "not a ROS bag (no '#ROSBAG V2.0' signature)");
  }

  std::uint64_t data_offset = 0;
  std::uint32_t data_size = 0;
  const RecordHeader bag_header = ReadRecordHeader(kMagicSize, &data_offset, &data_size);
  std::uint64_t index_pos = 0;
  std::uint32_t conn_count = 0, chunk_count = 0;
  try {
    if (bag_header.Op() != kOpBagHeader) throw FormatError("first record is not a bag header");
    index_pos = bag_header.U64("index_pos");
    conn_count = bag_header.U32("conn_count");
    chunk_count = bag_header.U32("chunk_count");
  } catch (const FormatError& e) {
    Fail(BagError::Kind::kCorrupt, std::string("bag header: ") + e.what());
  }
  first_record = data_offset + data_size;
  if (first_record > file_size)
    Fail(BagError::Kind::kTruncated, "truncated: ends inside its bag header");

  std::string problem;
  BagError::Kind kind = BagError::Kind::kTruncated;
  bool no_index = true;
  if (index_pos == 0) {
    problem = "has no index (the recording was not closed)";
  } else if (index_pos >= file_size) {
    problem = "is truncated: its index should start at " + At(index_pos) +
              " but the file has " + std::to_string(file_size) + " bytes";
  } else if (index_pos < first_record) {
    problem = "has an index position inside its header";
    kind = BagError::Kind::kCorrupt;
  } else {
    no_index = false;
    try {
      CheckStructure(index_pos, conn_count, chunk_count);
    } catch (const BagError& e) {
      problem = std::string(e.what()).substr(path.size() + 2);
      kind = e.kind();
    }
  }
  if (problem.empty()) {
    OpenWithRosbag();
    return;
  }
  if (!options.allow_partial) {
    if (no_index) WalkRecords();  // names the damaged chunk when there is one
    Fail(kind, problem);
  }
  damage = OneLine(path + ": " + problem);
  OpenPartial();
}

// ------------------------------------------------------------ shared by both paths

bool BagReader::Impl::IsDepthImage(const TopicParts& t) {
  return t.stream_type == "Depth" && t.rest == "image/data";
}

bool BagReader::Impl::IsMetadata(const std::string& topic, const TopicParts& t) {
  if (t.device >= 0 && t.sensor < 0)
    return topic == "/device_" + std::to_string(t.device) + "/info";
  if (t.sensor >= 0 && !t.option.empty()) return t.rest == "value" || t.rest == "description";
  return t.sensor >= 0 && (t.rest == "info" || t.rest == "info/camera_info");
}

void BagReader::Impl::ChooseDepth() {
  for (const auto& [id, c] : conns) {
    if (!IsDepthImage(c.parts)) continue;
    const TopicParts& best = conns[depth_conn].parts;
    if (!has_depth || std::make_pair(c.parts.sensor, c.parts.stream_index) <
                          std::make_pair(best.sensor, best.stream_index)) {
      has_depth = true;
      depth_conn = id;
    }
  }
}

void BagReader::Impl::ProcessMetadata(const std::string& topic, const TopicParts& t,
                                      const std::uint8_t* data, std::size_t size) {
  if (t.device >= 0 && t.sensor < 0 && topic == "/device_" + std::to_string(t.device) + "/info") {
    std::string key, value;
    DecodeKeyValue(data, size, &key, &value);
    device_info[t.device][key] = value;
  } else if (t.sensor >= 0 && !t.option.empty()) {
    if (t.rest == "value") {
      sensor_options[t.sensor][t.option] = DecodeFloat32(data, size);
    } else if (t.rest == "description") {
      option_descriptions[t.sensor][t.option] = DecodeString(data, size);
    }
  } else if (t.sensor >= 0 && t.stream_type.empty() && t.rest == "info") {
    std::string key, value;
    DecodeKeyValue(data, size, &key, &value);
    sensor_info[t.sensor][key] = value;
  } else if (!t.stream_type.empty() && t.rest == "info") {
    stream_infos[{t.sensor, t.stream_type, t.stream_index}] = DecodeStreamInfo(data, size);
  } else if (!t.stream_type.empty() && t.rest == "info/camera_info") {
    camera_infos[{t.sensor, t.stream_type, t.stream_index}] = DecodeCameraInfo(data, size);
  }
}

void BagReader::Impl::FirstFrame(const std::uint8_t* data, std::size_t size) {
  const ImageView v = DecodeImage(data, size);
  info.first_timestamp_ms = info.last_timestamp_ms = v.stamp_ms;
  info.depth.encoding = v.encoding;  // the frames' own encoding wins over the stream info
  info.depth.width = static_cast<int>(v.width);
  info.depth.height = static_cast<int>(v.height);
  first_frame_has_units = v.has_depth_units;
  if (first_frame_has_units) info.depth_units_m = CheckedUnits(v);
}

void BagReader::Impl::BuildInfo(bool first_seen) {
  info.file = path;
  for (const auto& [id, c] : conns) {
    const TopicParts& t = c.parts;
    const bool data = t.rest == "image/data" || t.rest == "imu/data" ||
                      t.rest == "pose/transform/data";
    if (t.stream_type.empty() || !data) continue;
    StreamInfo s;
    s.topic = c.topic;
    s.sensor_index = t.sensor;
    s.stream_type = t.stream_type;
    s.stream_index = t.stream_index;
    s.messages = c.messages;
    const StreamKey key{t.sensor, t.stream_type, t.stream_index};
    if (stream_infos.count(key)) {
      s.encoding = stream_infos[key].encoding;
      s.fps = static_cast<int>(stream_infos[key].fps);
    }
    if (camera_infos.count(key)) {
      s.width = static_cast<int>(camera_infos[key].width);
      s.height = static_cast<int>(camera_infos[key].height);
    }
    if (has_depth && id == depth_conn) {
      if (first_seen && info.depth.width > 0) {
        s.width = info.depth.width;
        s.height = info.depth.height;
      }
      if (first_seen && !info.depth.encoding.empty() && s.encoding != info.depth.encoding)
        s.encoding = info.depth.encoding;  // the frames' own encoding wins
      info.depth = s;
      info.depth_frames = s.messages;
    }
    info.streams.push_back(s);
  }
  if (!has_depth) {
    for (const auto& entry : stream_infos)
      if (std::get<1>(entry.first) == "Depth")
        Fail(BagError::Kind::kNoDepthStream,
             "depth stream Depth_" + std::to_string(std::get<2>(entry.first)) +
                 " of sensor " + std::to_string(std::get<0>(entry.first)) +
                 " is declared but recorded no frames");
    std::string names;
    for (const auto& s : info.streams)
      names += (names.empty() ? "" : ", ") + s.stream_type + "_" + std::to_string(s.stream_index);
    Fail(BagError::Kind::kNoDepthStream,
         "no depth stream (no /device_0/sensor_<n>/Depth_<i>/image/data topic; streams: " +
             (names.empty() ? std::string("none") : names) + ")");
  }
  if (!info.depth.encoding.empty() && !IsDepthEncoding(info.depth.encoding))
    Fail(BagError::Kind::kBadEncoding, "depth stream " + info.depth.topic + " is encoded as '" +
                                           OneLine(info.depth.encoding) +
                                           "', not 16-bit depth (mono16 or 16UC1)");
  const TopicParts& t = conns[depth_conn].parts;
  const int sensor = t.sensor;
  info.options = sensor_options[sensor];
  info.option_descriptions = option_descriptions[sensor];
  info.sensor = sensor_info[sensor];
  info.device = device_info[t.device];
  const auto units = info.options.find("Depth_Units");
  if (units != info.options.end()) {
    const std::string why = rules::kDepthUnitsM.Why(units->second);
    if (!why.empty())
      Fail(BagError::Kind::kCorrupt, "recorded option Depth_Units: " + why);
    fallback_units_m = units->second;
  }
  if (!first_seen || !first_frame_has_units) info.depth_units_m = fallback_units_m;
  const StreamKey key{sensor, t.stream_type, t.stream_index};
  if (camera_infos.count(key)) {
    const CameraInfoView& ci = camera_infos[key];
    camera::Intrinsics& in = info.depth_intrinsics;
    in.width = static_cast<int>(ci.width);
    in.height = static_cast<int>(ci.height);
    in.fx = ci.k[0];
    in.ppx = ci.k[2];
    in.fy = ci.k[4];
    in.ppy = ci.k[5];
    if (!camera::ParseDistortion(ci.distortion_model, &in.model))
      Fail(BagError::Kind::kCorrupt, "depth camera_info has unknown distortion model '" +
                                         OneLine(ci.distortion_model) + "'");
    in.coeffs = {0, 0, 0, 0, 0};
    for (std::size_t i = 0; i < ci.d.size() && i < in.coeffs.size(); ++i) in.coeffs[i] = ci.d[i];
    std::string why;
    if (!in.IsValid(&why)) Fail(BagError::Kind::kCorrupt, "depth camera_info: " + why);
    if (first_seen && info.depth.width > 0 &&
        (info.depth.width != in.width || info.depth.height != in.height))
      Fail(BagError::Kind::kCorrupt,
           "depth camera_info is for " + std::to_string(in.width) + " x " +
               std::to_string(in.height) + " px, the depth frames are " +
               std::to_string(info.depth.width) + " x " + std::to_string(info.depth.height) +
               " px");
    info.has_depth_intrinsics = true;
  }
}

// A frame's own depth units, refused when implausible (0, negative or NaN units are a damaged
// frame, not 1 mm).
double BagReader::Impl::CheckedUnits(const ImageView& v) const {
  const std::string why = rules::kDepthUnitsM.Why(v.depth_units);
  if (!why.empty())
    Fail(BagError::Kind::kCorrupt,
         "depth frame " + std::to_string(v.seq) + ": depth units " + why);
  return v.depth_units;
}

// One serialized sensor_msgs/Image of the depth stream into a frame (both paths).
void BagReader::Impl::DecodeDepth(const std::uint8_t* data, std::size_t size,
                                  const std::string& where, records::DepthFrame* frame) const {
  ImageView v;
  try {
    v = DecodeImage(data, size);
  } catch (const FormatError& e) {
    Fail(BagError::Kind::kCorrupt, where + ": " + e.what());
  }
  if (!IsDepthEncoding(v.encoding))
    Fail(BagError::Kind::kBadEncoding, "depth frame " + std::to_string(v.seq) +
                                           " is encoded as '" + OneLine(v.encoding) +
                                           "', not 16-bit depth (mono16 or 16UC1)");
  const std::uint64_t row = 2ull * v.width;
  if (v.width == 0 || v.height == 0 || v.width > 65535 || v.height > 65535 || v.step < row ||
      static_cast<std::uint64_t>(v.data_size) < v.step * (v.height - 1ull) + row)
    Fail(BagError::Kind::kCorrupt, "depth frame " + std::to_string(v.seq) + " has " +
                                       std::to_string(v.data_size) + " bytes for " +
                                       std::to_string(v.width) + "x" + std::to_string(v.height) +
                                       " pixels with a row step of " + std::to_string(v.step));
  frame->width = static_cast<int>(v.width);
  frame->height = static_cast<int>(v.height);
  frame->frame_number = v.seq;
  frame->timestamp_ms = v.stamp_ms;
  frame->depth_units_m = v.has_depth_units ? CheckedUnits(v) : fallback_units_m;
  frame->counts.resize(static_cast<std::size_t>(v.width) * v.height);
  std::uint8_t* dst = reinterpret_cast<std::uint8_t*>(frame->counts.data());
  if (v.step == row) {
    std::memcpy(dst, v.data, row * v.height);
  } else {
    for (std::uint32_t y = 0; y < v.height; ++y)
      std::memcpy(dst + y * row, v.data + static_cast<std::uint64_t>(y) * v.step, row);
  }
  if (v.big_endian)
    for (auto& c : frame->counts) c = static_cast<std::uint16_t>((c >> 8) | (c << 8));
}

BagReader::BagReader(const std::string& path, ReadOptions options) : impl_(new Impl) {
  impl_->path = path;
  impl_->options = options;
  impl_->Open();
}

BagReader::~BagReader() = default;

const BagInfo& BagReader::info() const { return impl_->info; }

const std::string& BagReader::damage() const { return impl_->damage; }

bool BagReader::Next(records::DepthFrame* frame) {
  Impl& d = *impl_;
  if (d.finished) return false;
  try {
    if (d.partial ? d.NextPartial(frame) : d.NextWithRosbag(frame)) return true;
    d.finished = true;
    return false;
  } catch (const BagError& e) {
    d.finished = true;
    if (!d.options.allow_partial) throw;
    d.damage = e.what();
    return false;
  }
}

}  // namespace depthbias::io
