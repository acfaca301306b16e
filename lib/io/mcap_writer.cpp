#include "io/mcap_writer.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <sys/stat.h>
#include <tuple>
#include <vector>

#include "io/chunk_compression.h"
#include "io/mcap_records.h"
#include "io/ros2_encode.h"
#include "io/temp_files.h"

namespace depthbias::io {
namespace {

constexpr char kFrameId[] = "camera_depth_optical_frame";
struct Topic {
  const char* name;
  const char* type;
};
constexpr Topic kTopics[3] = {{"/camera/camera/depth/image_rect_raw", "sensor_msgs/msg/Image"},
                              {"/camera/camera/depth/camera_info", "sensor_msgs/msg/CameraInfo"},
                              {"/parameter_events", "rcl_interfaces/msg/ParameterEvent"}};

}  // namespace

bool McapWriterConfig::IsValid(std::string* why) const {
  if (!bag.IsValid(why)) return false;
  if (std::fabs(bag.depth_units_m - 0.001) > 1e-9) {
    *why = "depth units must be 0.001 m for a ROS 2 16UC1 image (millimetres)";
    return false;
  }
  if (zstd_level < 1 || zstd_level > 19) {
    *why = "zstd level must be 1 to 19";
    return false;
  }
  return true;
}

struct McapWriter::Impl {
  std::string path, part;
  McapWriterConfig config;
  std::FILE* file = nullptr;
  std::uint64_t offset = 0;
  std::string summary_indexes;  // chunk index records
  std::map<std::uint16_t, std::uint64_t> counts;
  std::uint64_t messages = 0, chunks = 0, start_ns = 0, end_ns = 0;
  std::uint32_t sequence = 0;
  bool finished = false, committed = false;

  [[noreturn]] void Fail(const std::string& what) {
    throw BagError(BagError::Kind::kWrite, path, what);
  }
  void Put(const std::string& bytes) {
    if (std::fwrite(bytes.data(), 1, bytes.size(), file) != bytes.size())
      Fail(std::string("cannot write: ") + std::strerror(errno));
    offset += bytes.size();
  }
  // One chunk holding the messages given (channel, time, data), its message indexes after it.
  void Chunk(const std::vector<std::tuple<std::uint16_t, std::uint64_t, std::string>>& msgs) {
    std::string records;
    std::map<std::uint16_t, std::string> index;  // channel → (time, offset) entries
    std::uint64_t t0 = ~0ull, t1 = 0;
    for (const auto& [channel, t, data] : msgs) {
      std::string content;
      mcap::PutU16(&content, channel);
      mcap::PutU32(&content, ++sequence);
      mcap::PutU64(&content, t);
      mcap::PutU64(&content, t);
      content += data;
      mcap::PutU64(&index[channel], t);
      mcap::PutU64(&index[channel], records.size());
      mcap::PutRecord(&records, mcap::kMessage, content);
      ++counts[channel];
      ++messages;
      t0 = std::min(t0, t);
      t1 = std::max(t1, t);
    }
    if (messages == msgs.size()) start_ns = t0;
    end_ns = std::max(end_ns, t1);
    const std::string compression = config.zstd ? "zstd" : "";
    const std::string body = config.zstd ? CompressZstd(records, config.zstd_level) : records;
    std::string chunk;
    mcap::PutU64(&chunk, t0);
    mcap::PutU64(&chunk, t1);
    mcap::PutU64(&chunk, records.size());
    mcap::PutU32(&chunk, Crc32(reinterpret_cast<const std::uint8_t*>(records.data()),
                               records.size()));
    mcap::PutString(&chunk, compression);
    mcap::PutU64(&chunk, body.size());
    chunk += body;
    const std::uint64_t chunk_start = offset;
    std::string out;
    mcap::PutRecord(&out, mcap::kChunk, chunk);
    Put(out);
    const std::uint64_t index_start = offset;
    std::string ci_offsets;
    for (const auto& [channel, entries] : index) {
      mcap::PutU16(&ci_offsets, channel);
      mcap::PutU64(&ci_offsets, offset);
      std::string mi;
      mcap::PutU16(&mi, channel);
      mcap::PutU32(&mi, static_cast<std::uint32_t>(entries.size()));
      mi += entries;
      std::string rec;
      mcap::PutRecord(&rec, mcap::kMessageIndex, mi);
      Put(rec);
    }
    std::string ci;
    mcap::PutU64(&ci, t0);
    mcap::PutU64(&ci, t1);
    mcap::PutU64(&ci, chunk_start);
    mcap::PutU64(&ci, out.size());
    mcap::PutU32(&ci, static_cast<std::uint32_t>(ci_offsets.size()));
    ci += ci_offsets;
    mcap::PutU64(&ci, offset - index_start);
    mcap::PutString(&ci, compression);
    mcap::PutU64(&ci, body.size());
    mcap::PutU64(&ci, records.size());
    mcap::PutRecord(&summary_indexes, mcap::kChunkIndex, ci);
    ++chunks;
  }
  std::string SchemasAndChannels() const {
    std::string out;
    for (std::uint16_t i = 0; i < 3; ++i) {
      std::string s;
      mcap::PutU16(&s, i + 1);
      mcap::PutString(&s, kTopics[i].type);
      mcap::PutString(&s, "ros2msg");
      mcap::PutString(&s, ros2::MessageDefinition(kTopics[i].type));
      mcap::PutRecord(&out, mcap::kSchema, s);
    }
    for (std::uint16_t i = 0; i < 3; ++i) {
      std::string c;
      mcap::PutU16(&c, i);
      mcap::PutU16(&c, i + 1);
      mcap::PutString(&c, kTopics[i].name);
      mcap::PutString(&c, "cdr");
      std::string meta;
      mcap::PutString(&meta, "offered_qos_profiles");
      mcap::PutString(&meta, "");
      mcap::PutU32(&c, static_cast<std::uint32_t>(meta.size()));
      c += meta;
      mcap::PutRecord(&out, mcap::kChannel, c);
    }
    return out;
  }
};

McapWriter::McapWriter(const std::string& path, McapWriterConfig config)
    : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.path = path;
  d.config = std::move(config);
  std::string why;
  if (!d.config.IsValid(&why)) d.Fail(why);
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
    d.Fail("exists and is not a regular file");
  d.part = path + ".part";
  d.file = std::fopen(d.part.c_str(), "wb");
  if (!d.file) d.Fail(std::string("cannot create: ") + std::strerror(errno));
  RegisterTempFile(d.part);
  std::string head(reinterpret_cast<const char*>(mcap::kMagic), 8);
  std::string header;
  mcap::PutString(&header, "ros2");
  mcap::PutString(&header, "depthbias");
  mcap::PutRecord(&head, mcap::kHeader, header);
  head += d.SchemasAndChannels();
  d.Put(head);
}

McapWriter::~McapWriter() {
  if (impl_->file) std::fclose(impl_->file);
  if (!impl_->committed) {
    std::remove(impl_->part.c_str());
    UnregisterTempFile(impl_->part);
  }
}

void McapWriter::Write(const records::DepthFrame& frame) {
  Impl& d = *impl_;
  if (d.finished) d.Fail("write after finish");
  if (frame.width != d.config.bag.intrinsics.width ||
      frame.height != d.config.bag.intrinsics.height)
    d.Fail("frame of " + std::to_string(frame.width) + "x" + std::to_string(frame.height) +
           " px in a recording of " + std::to_string(d.config.bag.intrinsics.width) + "x" +
           std::to_string(d.config.bag.intrinsics.height));
  const std::uint64_t t = static_cast<std::uint64_t>(
      std::llround(std::max(0.0, frame.timestamp_ms) * 1e6)) + 1000000000ull;
  std::vector<std::tuple<std::uint16_t, std::uint64_t, std::string>> msgs;
  if (d.messages == 0) {
    std::vector<std::pair<std::string, std::int64_t>> params;
    const auto& o = d.config.bag.options;
    if (o.count("Visual_Preset"))
      params.push_back({"depth_module.visual_preset", std::llround(o.at("Visual_Preset"))});
    if (o.count("Emitter_Enabled"))
      params.push_back({"depth_module.emitter_enabled", std::llround(o.at("Emitter_Enabled"))});
    if (!params.empty())
      msgs.emplace_back(2, t, ros2::EncodeParameterEvent("/camera/camera", params,
                                                         static_cast<std::int64_t>(t)));
  }
  msgs.emplace_back(1, t, ros2::EncodeCameraInfo(d.config.bag.intrinsics,
                                                 static_cast<std::int64_t>(t), kFrameId));
  msgs.emplace_back(0, t, ros2::EncodeImage(frame, static_cast<std::int64_t>(t), kFrameId));
  d.Chunk(msgs);
}

void McapWriter::Finish() {
  Impl& d = *impl_;
  if (d.finished) return;
  std::string out;
  mcap::PutU32(&out, 0);  // data section CRC: not computed
  std::string data_end;
  mcap::PutRecord(&data_end, mcap::kDataEnd, out);
  d.Put(data_end);
  const std::uint64_t summary_start = d.offset;
  std::string summary = d.SchemasAndChannels();
  std::string stats;
  mcap::PutU64(&stats, d.messages);
  mcap::PutU16(&stats, 3);
  mcap::PutU32(&stats, 3);
  mcap::PutU32(&stats, 0);
  mcap::PutU32(&stats, 0);
  mcap::PutU32(&stats, static_cast<std::uint32_t>(d.chunks));
  mcap::PutU64(&stats, d.start_ns);
  mcap::PutU64(&stats, d.end_ns);
  std::string counts;
  for (const auto& [channel, n] : d.counts) {
    mcap::PutU16(&counts, channel);
    mcap::PutU64(&counts, n);
  }
  mcap::PutU32(&stats, static_cast<std::uint32_t>(counts.size()));
  stats += counts;
  mcap::PutRecord(&summary, mcap::kStatistics, stats);
  summary += d.summary_indexes;
  d.Put(summary);
  std::string footer;
  mcap::PutU64(&footer, summary_start);
  mcap::PutU64(&footer, 0);  // no summary offset section
  mcap::PutU32(&footer, 0);  // summary CRC: not computed
  std::string tail;
  mcap::PutRecord(&tail, mcap::kFooter, footer);
  tail.append(reinterpret_cast<const char*>(mcap::kMagic), 8);
  d.Put(tail);
  if (std::fflush(d.file) != 0 || std::fclose(d.file) != 0) {
    d.file = nullptr;
    d.Fail(std::string("cannot write: ") + std::strerror(errno));
  }
  d.file = nullptr;
  d.finished = true;
}

void McapWriter::Commit() {
  Impl& d = *impl_;
  Finish();
  if (std::rename(d.part.c_str(), d.path.c_str()) != 0)
    d.Fail(std::string("cannot rename ") + d.part + ": " + std::strerror(errno));
  UnregisterTempFile(d.part);
  d.committed = true;
}

void McapWriter::Close() { Commit(); }

}  // namespace depthbias::io
