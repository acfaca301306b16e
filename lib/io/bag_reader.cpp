// Streaming reader of RealSense ROS1 bags. The bag's index (connections and per-chunk message
// counts) is read at open; frames are then decoded one chunk at a time, so memory holds one
// chunk (one or two frames) whatever the length of the recording. LZ4 chunks (roslz4's format,
// which is the LZ4 frame format) are decompressed with liblz4's frame API, which checks them and
// is faster than roslz4's own decoder; BZ2 chunks with libbz2.

#include <bzlib.h>
#include <fcntl.h>
#include <lz4frame.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <sstream>
#include <tuple>

#include "io/bag.h"
#include "io/bag_records.h"

namespace depthbias::io {
namespace {

using namespace bag_detail;

constexpr std::uint32_t kMaxRecordHeaderBytes = 1u << 20;  // real headers hold a few fields
constexpr std::uint64_t kMaxChunkBytes = 1ull << 31;       // larger means a damaged size field
constexpr std::uint64_t kMaxIndexBytes = 1ull << 30;

std::string OneLine(std::string s) {
  std::replace(s.begin(), s.end(), '\n', ' ');
  std::replace(s.begin(), s.end(), '\r', ' ');
  return s;
}

std::string At(std::uint64_t offset) { return "byte " + std::to_string(offset); }

bool IsDepthEncoding(const std::string& e) { return e == "mono16" || e == "16UC1"; }

}  // namespace

BagError::BagError(Kind kind, const std::string& file, const std::string& what)
    : std::runtime_error(OneLine(file + ": " + what)), kind_(kind), file_(file) {}

struct BagReader::Impl {
  struct Connection {
    std::string topic;
    std::string type;
    TopicParts parts;
    std::uint64_t messages = 0;  // counted while scanning a bag read without its index
  };
  struct Message {
    std::uint32_t conn = 0;
    const std::uint8_t* data = nullptr;
    std::size_t size = 0;
  };
  // Position in the file and the decompressed chunk being read.
  struct Cursor {
    std::uint64_t next_record = 0;
    std::uint64_t chunk_pos = 0;
    std::vector<std::uint8_t> raw;
    std::vector<std::uint8_t> data;
    std::size_t size = 0;
    std::size_t pos = 0;
    bool loaded = false;
    bool cut = false;  // the chunk is cut short by the end of the file (partial read)
    std::map<std::uint32_t, std::uint32_t> seen;
  };
  using StreamKey = std::tuple<int, std::string, int>;  // sensor, type, index

  std::string path;
  ReadOptions options;
  int fd = -1;
  std::uint64_t file_size = 0;
  BagInfo info;
  std::map<std::uint32_t, Connection> conns;
  std::map<std::uint64_t, std::map<std::uint32_t, std::uint32_t>> chunk_counts;  // index
  std::uint64_t first_record = 0;
  std::uint64_t data_end = 0;
  bool has_depth = false;
  std::uint32_t depth_conn = 0;
  double fallback_units_m = 0.001;
  bool first_frame_has_units = false;
  std::string damage;
  Cursor cursor;
  bool finished = false;
  LZ4F_dctx* lz4 = nullptr;

  // Recorded metadata, gathered before the first depth frame.
  std::map<int, std::map<std::string, std::string>> device_info;
  std::map<int, std::map<std::string, std::string>> sensor_info;
  std::map<int, std::map<std::string, double>> sensor_options;
  std::map<int, std::map<std::string, std::string>> option_descriptions;
  std::map<StreamKey, StreamInfoView> stream_infos;
  std::map<StreamKey, CameraInfoView> camera_infos;

  ~Impl() {
    if (fd >= 0) ::close(fd);
    if (lz4) LZ4F_freeDecompressionContext(lz4);
  }

  // Decompresses one LZ4 frame; false on damaged data or a size other than expected.
  bool Lz4(const std::uint8_t* in, std::size_t in_size, std::uint8_t* out, std::size_t out_size) {
    if (!lz4 && LZ4F_isError(LZ4F_createDecompressionContext(&lz4, LZ4F_VERSION))) return false;
    LZ4F_resetDecompressionContext(lz4);
    std::size_t done_in = 0, done_out = 0;
    for (;;) {
      std::size_t dst = out_size - done_out, src = in_size - done_in;
      const std::size_t rc = LZ4F_decompress(lz4, out + done_out, &dst, in + done_in, &src, nullptr);
      if (LZ4F_isError(rc)) return false;
      done_in += src;
      done_out += dst;
      if (rc == 0) return done_out == out_size;  // end of frame
      if ((src == 0 && dst == 0) || done_in >= in_size) return false;  // stalled or cut short
    }
  }

  [[noreturn]] void Fail(BagError::Kind kind, const std::string& what) const {
    throw BagError(kind, path, what);
  }

  void ReadAt(std::uint64_t offset, std::size_t count, std::uint8_t* dst) const {
    std::size_t done = 0;
    while (done < count) {
      const ssize_t n = ::pread(fd, dst + done, count - done, static_cast<off_t>(offset + done));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) Fail(BagError::Kind::kCorrupt, "read error at " + At(offset) + ": " +
                                                    std::strerror(errno));
      if (n == 0) Fail(BagError::Kind::kTruncated, "truncated: ends early at " + At(offset + done));
      done += static_cast<std::size_t>(n);
    }
  }

  // Reads the header of the top-level record at offset. Returns its data offset and size.
  RecordHeader ReadRecordHeader(std::uint64_t offset, std::uint64_t* data_offset,
                                std::uint32_t* data_size) const {
    if (offset + 4 > file_size)
      Fail(BagError::Kind::kTruncated, "truncated: ends inside the record at " + At(offset));
    std::uint8_t b4[4];
    ReadAt(offset, 4, b4);
    const std::uint32_t header_size = ByteReader(b4, 4).U32();
    if (header_size > kMaxRecordHeaderBytes)
      Fail(BagError::Kind::kCorrupt, "record at " + At(offset) + " has a header of " +
                                         std::to_string(header_size) + " bytes");
    if (offset + 8 + header_size > file_size)
      Fail(BagError::Kind::kTruncated, "truncated: ends inside the record at " + At(offset));
    std::vector<std::uint8_t> h(header_size + 4);
    ReadAt(offset + 4, h.size(), h.data());
    RecordHeader header;
    try {
      header = RecordHeader(h.data(), header_size);
      header.Op();
    } catch (const FormatError& e) {
      Fail(BagError::Kind::kCorrupt, "record at " + At(offset) + ": " + e.what());
    }
    *data_size = ByteReader(h.data() + header_size, 4).U32();
    *data_offset = offset + 8 + header_size;
    return header;
  }

  void Open() {
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

    std::string index_problem;
    BagError::Kind index_kind = BagError::Kind::kTruncated;
    if (index_pos == 0) {
      index_problem = "has no index (the recording was not closed)";
    } else if (index_pos >= file_size) {
      index_problem = "is truncated: its index should start at " + At(index_pos) +
                      " but the file has " + std::to_string(file_size) + " bytes";
    } else if (index_pos < first_record) {
      index_problem = "has an index position inside its header";
      index_kind = BagError::Kind::kCorrupt;
    } else {
      try {
        ReadIndex(index_pos, conn_count, chunk_count);
      } catch (const FormatError& e) {
        index_problem = std::string("has a damaged index: ") + e.what();
        index_kind = BagError::Kind::kCorrupt;
      } catch (const BagError& e) {
        index_problem = "has a damaged index: " + std::string(e.what()).substr(path.size() + 2);
        index_kind = e.kind();
      }
    }

    if (index_problem.empty()) {
      data_end = index_pos;
    } else {
      conns.clear();
      chunk_counts.clear();
      data_end = file_size;
      if (!options.allow_partial) {
        WalkRecords();  // names the damaged chunk when there is one
        Fail(index_kind, index_problem);
      }
      info.indexed = false;
      damage = OneLine(path + ": " + index_problem);
    }
    Scan();
  }

  void ReadIndex(std::uint64_t index_pos, std::uint32_t conn_count, std::uint32_t chunk_count) {
    const std::uint64_t size = file_size - index_pos;
    if (size > kMaxIndexBytes) throw FormatError("index of " + std::to_string(size) + " bytes");
    std::vector<std::uint8_t> buf(size);
    ReadAt(index_pos, size, buf.data());
    ByteReader r(buf.data(), buf.size());
    std::uint32_t got_conns = 0, got_chunks = 0;
    while (r.remaining() > 0) {
      const std::uint32_t header_size = r.U32();
      const RecordHeader h(r.Bytes(header_size), header_size);
      const std::uint32_t data_size = r.U32();
      const std::uint8_t* data = r.Bytes(data_size);
      const std::uint8_t op = h.Op();
      if (op == kOpConnection) {
        Connection c;
        c.topic = h.Str("topic");
        const RecordHeader fields(data, data_size);
        c.type = fields.Has("type") ? fields.Str("type") : std::string();
        c.parts = ParseTopic(c.topic);
        conns[h.U32("conn")] = std::move(c);
        ++got_conns;
      } else if (op == kOpChunkInfo) {
        const std::uint64_t pos = h.U64("chunk_pos");
        const std::uint32_t n = h.U32("count");
        if (pos < first_record || pos >= index_pos)
          throw FormatError("chunk position out of range");
        ByteReader d(data, data_size);
        auto& counts = chunk_counts[pos];
        for (std::uint32_t i = 0; i < n; ++i) {
          const std::uint32_t conn = d.U32();
          counts[conn] = d.U32();
        }
        ++got_chunks;
      } else {
        throw FormatError("unexpected record in the index");
      }
    }
    if (got_conns != conn_count || got_chunks != chunk_count)
      throw FormatError("index lists " + std::to_string(got_conns) + " connections and " +
                        std::to_string(got_chunks) + " chunks, the bag header " +
                        std::to_string(conn_count) + " and " + std::to_string(chunk_count));
    for (const auto& [pos, counts] : chunk_counts)
      for (const auto& entry : counts)
        if (!conns.count(entry.first)) throw FormatError("index counts an unknown connection");
  }

  // Walks the top-level records without decompressing, to locate damage.
  void WalkRecords() const {
    std::uint64_t offset = first_record;
    while (offset < file_size) {
      std::uint64_t data_offset = 0;
      std::uint32_t data_size = 0;
      const RecordHeader h = ReadRecordHeader(offset, &data_offset, &data_size);
      if (data_offset + data_size > file_size) {
        const bool chunk = h.Op() == kOpChunk;
        Fail(BagError::Kind::kTruncated,
             std::string("truncated: ends in the middle of ") +
                 (chunk ? "the chunk" : "the record") + " at " + At(offset) + " (" +
                 std::to_string(file_size - data_offset) + " of " + std::to_string(data_size) +
                 " bytes present)");
      }
      offset = data_offset + data_size;
    }
  }

  // Loads the next chunk at or after c->next_record. False at the end of the chunk data.
  // With depth_only, skips the chunks the index says hold no depth frame (color, IMU, ...)
  // without reading them.
  bool LoadNextChunk(Cursor* c, bool depth_only = false) {
    while (c->next_record < data_end) {
      const std::uint64_t offset = c->next_record;
      std::uint64_t data_offset = 0;
      std::uint32_t data_size = 0;
      const RecordHeader h = ReadRecordHeader(offset, &data_offset, &data_size);
      std::uint8_t op = 0;
      std::string compression;
      std::uint32_t plain_size = 0;
      try {
        op = h.Op();
        if (op == kOpChunk) {
          compression = h.Str("compression");
          plain_size = h.U32("size");
        }
      } catch (const FormatError& e) {
        Fail(BagError::Kind::kCorrupt, "chunk at " + At(offset) + ": " + e.what());
      }
      const std::uint64_t end = data_offset + data_size;
      const bool cut = end > file_size;
      if (op != kOpChunk) {
        if (cut)
          Fail(BagError::Kind::kTruncated,
               "truncated: ends in the middle of the record at " + At(offset));
        c->next_record = end;
        continue;
      }
      if (depth_only && info.indexed && has_depth && !cut) {
        const auto counts = chunk_counts.find(offset);
        if (counts != chunk_counts.end() && !counts->second.count(depth_conn)) {
          c->next_record = end;
          continue;
        }
      }
      if (cut && !(options.allow_partial && compression == "none"))
        Fail(BagError::Kind::kTruncated,
             "truncated: ends in the middle of the chunk at " + At(offset) + " (" +
                 std::to_string(file_size - data_offset) + " of " + std::to_string(data_size) +
                 " bytes present)");
      const std::size_t stored = cut ? static_cast<std::size_t>(file_size - data_offset)
                                     : static_cast<std::size_t>(data_size);
      // LZ4 expands at most ~255 times: a larger claim is a damaged size field.
      if (compression == "lz4" && plain_size > 255ull * stored + 65536)
        Fail(BagError::Kind::kCorrupt, "chunk at " + At(offset) + " claims " +
                                           std::to_string(plain_size) + " bytes from " +
                                           std::to_string(stored) + " compressed");
      if (plain_size > kMaxChunkBytes)
        Fail(BagError::Kind::kCorrupt, "chunk at " + At(offset) + " claims " +
                                           std::to_string(plain_size) + " bytes");
      if (compression == "none") {
        if (!cut && plain_size != data_size)
          Fail(BagError::Kind::kCorrupt, "uncompressed chunk at " + At(offset) +
                                             " has inconsistent sizes");
        if (c->data.size() < stored) c->data.resize(stored);
        ReadAt(data_offset, stored, c->data.data());
        c->size = stored;
      } else if (compression == "lz4" || compression == "bz2") {
        if (c->raw.size() < stored) c->raw.resize(stored);
        ReadAt(data_offset, stored, c->raw.data());
        if (c->data.size() < plain_size) c->data.resize(plain_size);
        bool ok;
        if (compression == "lz4") {
          ok = Lz4(c->raw.data(), stored, c->data.data(), plain_size);
        } else {
          unsigned int out_size = plain_size;
          ok = BZ2_bzBuffToBuffDecompress(reinterpret_cast<char*>(c->data.data()), &out_size,
                                          reinterpret_cast<char*>(c->raw.data()),
                                          static_cast<unsigned int>(stored), 0, 0) == BZ_OK &&
               out_size == plain_size;
        }
        if (!ok)
          Fail(BagError::Kind::kCorrupt, compression + " chunk at " + At(offset) +
                                             " does not decompress (damaged data)");
        c->size = plain_size;
      } else {
        Fail(BagError::Kind::kCorrupt, "chunk at " + At(offset) + " has unknown compression '" +
                                           OneLine(compression) + "'");
      }
      if (compression != "none") info.compressed = true;
      c->chunk_pos = offset;
      c->pos = 0;
      c->cut = cut;
      c->loaded = true;
      c->seen.clear();
      c->next_record = cut ? file_size : end;
      return true;
    }
    return false;
  }

  // Next message of the loaded chunk; false when the chunk is done.
  bool NextInChunk(Cursor* c, Message* m) {
    auto damaged = [&](const std::string& what) {
      if (c->cut)
        Fail(BagError::Kind::kTruncated, "truncated: ends in the middle of the chunk at " +
                                             At(c->chunk_pos) + ", inside its record at offset " +
                                             std::to_string(c->pos));
      Fail(BagError::Kind::kCorrupt, "chunk at " + At(c->chunk_pos) + ": " + what);
    };
    while (c->pos < c->size) {
      ByteReader r(c->data.data() + c->pos, c->size - c->pos);
      RecordHeader h;
      std::uint32_t data_size = 0;
      const std::uint8_t* data = nullptr;
      std::uint8_t op = 0;
      std::uint32_t conn = 0;
      try {
        const std::uint32_t header_size = r.U32();
        h = RecordHeader(r.Bytes(header_size), header_size);
        data_size = r.U32();
        data = r.Bytes(data_size);
        op = h.Op();
        if (op != kOpMessage && op != kOpConnection)
          throw FormatError("unexpected record op " + std::to_string(op));
        conn = h.U32("conn");
        if (op == kOpConnection) RegisterConnection(conn, h, data, data_size);
      } catch (const FormatError& e) {
        damaged(std::string("record at offset ") + std::to_string(c->pos) + ": " + e.what());
      }
      c->pos += r.pos();
      if (op == kOpConnection) continue;
      if (!conns.count(conn)) damaged("message on unknown connection " + std::to_string(conn));
      ++c->seen[conn];
      *m = {conn, data, data_size};
      return true;
    }
    c->loaded = false;
    if (c->cut) damaged("file ends");
    const auto it = chunk_counts.find(c->chunk_pos);
    if (info.indexed && (it == chunk_counts.end() || it->second != c->seen))
      Fail(BagError::Kind::kCorrupt, "chunk at " + At(c->chunk_pos) +
                                         " holds other messages than the index lists");
    return false;
  }

  void RegisterConnection(std::uint32_t id, const RecordHeader& h, const std::uint8_t* data,
                          std::size_t size) {
    if (conns.count(id)) return;
    Connection c;
    c.topic = h.Str("topic");
    const RecordHeader fields(data, size);
    c.type = fields.Has("type") ? fields.Str("type") : std::string();
    c.parts = ParseTopic(c.topic);
    conns[id] = std::move(c);
  }

  bool NextMessage(Cursor* c, Message* m, bool depth_only = false) {
    for (;;) {
      if (c->loaded && NextInChunk(c, m)) return true;
      if (!LoadNextChunk(c, depth_only)) return false;
    }
  }

  static bool IsDepthImage(const Connection& c) {
    return c.parts.stream_type == "Depth" && c.parts.rest == "image/data";
  }

  void ChooseDepth() {
    for (const auto& [id, c] : conns) {
      if (!IsDepthImage(c)) continue;
      const TopicParts& best = conns[depth_conn].parts;
      if (!has_depth || std::make_pair(c.parts.sensor, c.parts.stream_index) <
                            std::make_pair(best.sensor, best.stream_index)) {
        has_depth = true;
        depth_conn = id;
      }
    }
  }

  void ProcessMetadata(const Connection& c, const Message& m) {
    const TopicParts& t = c.parts;
    ByteReader r(m.data, m.size);
    const bool device_info_topic =
        t.device >= 0 && t.sensor < 0 && c.topic == "/device_" + std::to_string(t.device) + "/info";
    if (device_info_topic) {
      std::string key = r.String();
      device_info[t.device][key] = r.String();
    } else if (t.sensor >= 0 && !t.option.empty()) {
      if (t.rest == "value") {
        sensor_options[t.sensor][t.option] = r.F32();
      } else if (t.rest == "description") {
        option_descriptions[t.sensor][t.option] = r.String();
      }
    } else if (t.sensor >= 0 && t.stream_type.empty() && t.rest == "info") {
      std::string key = r.String();
      sensor_info[t.sensor][key] = r.String();
    } else if (!t.stream_type.empty() && t.rest == "info") {
      stream_infos[{t.sensor, t.stream_type, t.stream_index}] = DecodeStreamInfo(m.data, m.size);
    } else if (!t.stream_type.empty() && t.rest == "info/camera_info") {
      camera_infos[{t.sensor, t.stream_type, t.stream_index}] = DecodeCameraInfo(m.data, m.size);
    }
  }

  // Reads the metadata recorded before the first depth frame, and that frame's header. Without
  // an index (partial read), scans the whole file to count messages and find the last frame.
  void Scan() {
    if (info.indexed) ChooseDepth();
    Cursor c;
    c.next_record = first_record;
    Message m;
    bool first_seen = false;
    try {
      while (NextMessage(&c, &m)) {
        Connection& conn = conns[m.conn];
        if (!info.indexed) {
          ++conn.messages;
          if (!has_depth) ChooseDepth();
        }
        if (has_depth && m.conn == depth_conn) {
          if (!first_seen) {
            try {
              FirstFrame(m);
            } catch (const FormatError& e) {
              Fail(BagError::Kind::kCorrupt, std::string("first depth frame: ") + e.what());
            }
            first_seen = true;
            if (info.indexed) break;
          } else {
            std::uint32_t seq;
            try {
              DecodeStamp(m.data, m.size, &seq, &info.last_timestamp_ms);
            } catch (const FormatError& e) {
              Fail(BagError::Kind::kCorrupt, std::string("depth frame: ") + e.what());
            }
          }
        } else if (!first_seen) {
          try {
            ProcessMetadata(conn, m);
          } catch (const FormatError& e) {
            Fail(BagError::Kind::kCorrupt, "message on " + conn.topic + ": " + e.what());
          }
        }
      }
    } catch (const BagError& e) {
      if (!options.allow_partial) throw;
      damage = e.what();
      finished = info.indexed;  // damage before the first frame of an indexed bag: nothing to read
      if (!info.indexed) ChooseDepth();
      if (!has_depth || (info.indexed && !first_seen)) throw;  // nothing readable before it
    }
    if (!has_depth) ChooseDepth();
    BuildInfo(first_seen);
    if (info.indexed && info.depth_frames > 0) LastFrame();
  }

  void FirstFrame(const Message& m) {
    const ImageView v = DecodeImage(m.data, m.size);
    info.first_timestamp_ms = info.last_timestamp_ms = v.stamp_ms;
    info.depth.encoding = v.encoding;  // the frames' own encoding wins over the stream info
    info.depth.width = static_cast<int>(v.width);
    info.depth.height = static_cast<int>(v.height);
    first_frame_has_units = v.has_depth_units && std::isfinite(v.depth_units) && v.depth_units > 0;
    if (first_frame_has_units) info.depth_units_m = v.depth_units;
  }

  void LastFrame() {
    std::uint64_t last_chunk = 0;
    for (const auto& [pos, counts] : chunk_counts) {
      const auto it = counts.find(depth_conn);
      if (it != counts.end() && it->second > 0) last_chunk = pos;
    }
    Cursor c;
    c.next_record = last_chunk;
    Message m;
    if (!LoadNextChunk(&c)) return;
    try {
      while (NextInChunk(&c, &m)) {
        if (m.conn != depth_conn) continue;
        std::uint32_t seq;
        DecodeStamp(m.data, m.size, &seq, &info.last_timestamp_ms);
      }
    } catch (const FormatError& e) {
      Fail(BagError::Kind::kCorrupt, std::string("last depth frame: ") + e.what());
    }
  }

  void BuildInfo(bool first_seen) {
    info.file = path;
    std::map<std::uint32_t, std::uint64_t> counts;
    for (const auto& [pos, per_conn] : chunk_counts)
      for (const auto& [id, n] : per_conn) counts[id] += n;
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
      s.messages = info.indexed ? counts[id] : c.messages;
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
    if (units != info.options.end() && std::isfinite(units->second) && units->second > 0)
      fallback_units_m = units->second;
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
      info.has_depth_intrinsics = true;
    }
  }

  void DecodeDepth(const Message& m, camera::DepthFrame* frame) {
    ImageView v;
    try {
      v = DecodeImage(m.data, m.size);
    } catch (const FormatError& e) {
      Fail(BagError::Kind::kCorrupt, "depth frame in chunk at " + At(cursor.chunk_pos) + ": " +
                                         e.what());
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
    frame->depth_units_m = (v.has_depth_units && std::isfinite(v.depth_units) && v.depth_units > 0)
                               ? static_cast<double>(v.depth_units)
                               : fallback_units_m;
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
};

std::string PresetName(double visual_preset) {
  static const char* const kNames[] = {"Custom", "Default", "Hand", "HA",
                                       "HD", "Medium Density", "Remove IR Pattern"};
  const double rounded = std::round(visual_preset);
  if (rounded == visual_preset && rounded >= 0 && rounded <= 6)
    return kNames[static_cast<int>(rounded)];
  std::ostringstream name;
  name << "preset " << visual_preset;
  return name.str();
}

BagReader::BagReader(const std::string& path, ReadOptions options) : impl_(new Impl) {
  impl_->path = path;
  impl_->options = options;
  impl_->Open();
  impl_->cursor.next_record = impl_->first_record;
}

BagReader::~BagReader() = default;

const BagInfo& BagReader::info() const { return impl_->info; }

const std::string& BagReader::damage() const { return impl_->damage; }

bool BagReader::Next(camera::DepthFrame* frame) {
  Impl& d = *impl_;
  if (d.finished) return false;
  try {
    Impl::Message m;
    while (d.NextMessage(&d.cursor, &m, /*depth_only=*/true)) {
      if (m.conn != d.depth_conn) continue;
      d.DecodeDepth(m, frame);
      return true;
    }
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
