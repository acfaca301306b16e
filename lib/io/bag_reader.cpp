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

#include <bzlib.h>
#include <console_bridge/console.h>
#include <fcntl.h>
#include <ros/exception.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <sensor_msgs/Image.h>
#include <roslz4/lz4s.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <set>
#include <sstream>
#include <tuple>

#include "io/bag.h"
#include "io/bag_records.h"
#include "io/ranges.h"
#include "io/rosbag_guard.h"

namespace depthbias::io {
namespace {

using namespace bag_detail;

constexpr std::uint32_t kMaxRecordHeaderBytes = 1u << 20;  // real headers hold a few fields
constexpr std::uint64_t kMaxChunkBytes = 1ull << 28;       // larger means a damaged size field
constexpr std::uint64_t kMaxIndexBytes = 1ull << 30;

std::string OneLine(std::string s) {
  std::replace(s.begin(), s.end(), '\n', ' ');
  std::replace(s.begin(), s.end(), '\r', ' ');
  return s;
}

std::string At(std::uint64_t offset) { return "byte " + std::to_string(offset); }

bool IsDepthEncoding(const std::string& e) { return e == "mono16" || e == "16UC1"; }

// rosbag::MessageInstance::write() target: the serialized bytes of one message, in a buffer
// reused from message to message.
struct ByteSink {
  std::vector<std::uint8_t>* bytes;
  std::uint8_t* advance(std::uint32_t n) {
    if (n > kMaxChunkBytes) throw FormatError("message of " + std::to_string(n) + " bytes");
    bytes->resize(n);
    return bytes->data();
  }
};

// A depth image as rosbag's MessageInstance::instantiate() sees it: instead of building a
// sensor_msgs::Image (a copy of the pixels), its deserializer hands the serialized bytes, in
// place in rosbag's chunk buffer, to the decoder of the frame being read.
struct DepthImageBytes {};

struct DepthDecoder {
  virtual void Decode(const std::uint8_t* data, std::size_t size) = 0;
  virtual ~DepthDecoder() = default;
};
thread_local DepthDecoder* tl_depth_decoder = nullptr;

}  // namespace
}  // namespace depthbias::io

namespace ros {
namespace message_traits {
template <>
struct MD5Sum<depthbias::io::DepthImageBytes> {
  static const char* value() { return MD5Sum<sensor_msgs::Image>::value(); }
  static const char* value(const depthbias::io::DepthImageBytes&) { return value(); }
};
}  // namespace message_traits
namespace serialization {
template <>
struct Serializer<depthbias::io::DepthImageBytes> {
  template <typename Stream>
  static void read(Stream& stream, depthbias::io::DepthImageBytes&) {
    const std::uint32_t size = stream.getLength();
    const std::uint8_t* data = stream.advance(size);
    depthbias::io::tl_depth_decoder->Decode(data, size);
  }
};
}  // namespace serialization
}  // namespace ros

namespace depthbias::io {

BagError::BagError(Kind kind, const std::string& file, const std::string& what)
    : std::runtime_error(OneLine(file + ": " + what)), kind_(kind), file_(file) {}

struct BagReader::Impl {
  struct Connection {
    std::string topic;
    TopicParts parts;
    std::uint64_t messages = 0;
  };
  struct Message {
    std::uint32_t conn = 0;
    const std::uint8_t* data = nullptr;
    std::size_t size = 0;
  };
  // Partial path: position in the file and the decompressed chunk being read.
  struct Cursor {
    std::uint64_t next_record = 0;
    std::uint64_t chunk_pos = 0;
    std::vector<std::uint8_t> raw;
    std::vector<std::uint8_t> data;
    std::size_t size = 0;
    std::size_t pos = 0;
    bool loaded = false;
    bool cut = false;  // the chunk is cut short by the end of the file
  };
  struct ChunkHead {
    std::string compression;
    std::uint32_t plain_size = 0;
    std::uint64_t data_offset = 0;
    std::uint32_t data_size = 0;
  };
  using StreamKey = std::tuple<int, std::string, int>;  // sensor, type, index

  std::string path;
  ReadOptions options;
  int fd = -1;
  std::uint64_t file_size = 0;
  std::uint64_t first_record = 0;
  BagInfo info;
  std::map<std::uint32_t, Connection> conns;
  bool has_depth = false;
  std::uint32_t depth_conn = 0;
  double fallback_units_m = 0.001;
  bool first_frame_has_units = false;
  std::string damage;
  bool finished = false;
  std::vector<std::uint8_t> bytes;  // serialized message being decoded

  // rosbag path.
  std::unique_ptr<bag_detail::GuardedBag> bag;
  std::unique_ptr<rosbag::View> frames;
  rosbag::View::iterator next_frame;
  std::uint64_t frames_read = 0;

  // Partial path.
  bool partial = false;
  Cursor cursor;

  // Recorded metadata, gathered before the first depth frame.
  std::map<int, std::map<std::string, std::string>> device_info;
  std::map<int, std::map<std::string, std::string>> sensor_info;
  std::map<int, std::map<std::string, double>> sensor_options;
  std::map<int, std::map<std::string, std::string>> option_descriptions;
  std::map<StreamKey, StreamInfoView> stream_infos;
  std::map<StreamKey, CameraInfoView> camera_infos;

  ~Impl() {
    frames.reset();
    bag.reset();
    if (fd >= 0) ::close(fd);
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

  // Checks a chunk record's header against the file. A chunk cut short by the end of the file
  // is an error unless allow_cut (partial reads of an uncompressed chunk).
  ChunkHead CheckChunk(std::uint64_t offset, const RecordHeader& h, std::uint64_t data_offset,
                       std::uint32_t data_size, bool allow_cut) const {
    ChunkHead c;
    c.data_offset = data_offset;
    c.data_size = data_size;
    try {
      c.compression = h.Str("compression");
      c.plain_size = h.U32("size");
    } catch (const FormatError& e) {
      Fail(BagError::Kind::kCorrupt, "chunk at " + At(offset) + ": " + e.what());
    }
    const bool cut = data_offset + data_size > file_size;
    if (cut && !(allow_cut && c.compression == "none"))
      Fail(BagError::Kind::kTruncated,
           "truncated: ends in the middle of the chunk at " + At(offset) + " (" +
               std::to_string(file_size - data_offset) + " of " + std::to_string(data_size) +
               " bytes present)");
    if (c.compression == "none") {
      if (c.plain_size != data_size)
        Fail(BagError::Kind::kCorrupt,
             "uncompressed chunk at " + At(offset) + " has inconsistent sizes");
    } else if (c.compression == "lz4") {
      // LZ4 expands at most ~255 times: a larger claim is a damaged size field.
      if (c.plain_size > 255ull * data_size + 65536)
        Fail(BagError::Kind::kCorrupt, "chunk at " + At(offset) + " claims " +
                                           std::to_string(c.plain_size) + " bytes from " +
                                           std::to_string(data_size) + " compressed");
    } else if (c.compression != "bz2") {
      Fail(BagError::Kind::kCorrupt, "chunk at " + At(offset) + " has unknown compression '" +
                                         OneLine(c.compression) + "'");
    }
    if (c.plain_size > kMaxChunkBytes)
      Fail(BagError::Kind::kCorrupt,
           "chunk at " + At(offset) + " claims " + std::to_string(c.plain_size) + " bytes");
    return c;
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

  // ------------------------------------------------------------ structural check

  // Everything rosbag::Bag reads without checking: the index (connections, chunk infos), every
  // chunk's header and the index data after it, and, in uncompressed chunks, the record of every
  // indexed message. Nothing is decompressed. Throws BagError.
  void CheckStructure(std::uint64_t index_pos, std::uint32_t conn_count,
                      std::uint32_t chunk_count) {
    std::set<std::uint32_t> index_conns;
    std::map<std::uint64_t, std::map<std::uint32_t, std::uint32_t>> chunk_counts;
    try {
      ReadIndex(index_pos, conn_count, chunk_count, &index_conns, &chunk_counts);
    } catch (const FormatError& e) {
      Fail(BagError::Kind::kCorrupt, std::string("has a damaged index: ") + e.what());
    }
    std::uint64_t offset = first_record;
    std::size_t chunks = 0;
    std::vector<std::uint8_t> entries;
    while (offset < index_pos) {
      std::uint64_t data_offset = 0;
      std::uint32_t data_size = 0;
      const RecordHeader h = ReadRecordHeader(offset, &data_offset, &data_size);
      const std::uint64_t end = data_offset + data_size;
      if (end > index_pos)
        Fail(BagError::Kind::kCorrupt, "record at " + At(offset) + " runs into the index");
      std::uint8_t op = 0;
      try {
        op = h.Op();
      } catch (const FormatError& e) {
        Fail(BagError::Kind::kCorrupt, "record at " + At(offset) + ": " + e.what());
      }
      if (op != kOpChunk) {
        if (op != kOpConnection && op != kOpIndexData)
          Fail(BagError::Kind::kCorrupt,
               "unexpected record op " + std::to_string(op) + " at " + At(offset));
        offset = end;
        continue;
      }
      const ChunkHead chunk = CheckChunk(offset, h, data_offset, data_size, false);
      if (chunk.compression != "none") info.compressed = true;
      const auto listed = chunk_counts.find(offset);
      if (listed == chunk_counts.end())
        Fail(BagError::Kind::kCorrupt, "chunk at " + At(offset) + " is not in the index");
      ++chunks;
      // The index data records after the chunk: one per connection it holds.
      std::uint64_t at = end;
      for (std::size_t i = 0; i < listed->second.size(); ++i) {
        std::uint64_t entries_offset = 0;
        std::uint32_t entries_size = 0;
        const RecordHeader ih = ReadRecordHeader(at, &entries_offset, &entries_size);
        std::uint32_t conn = 0, count = 0;
        try {
          if (ih.Op() != kOpIndexData) throw FormatError("not an index data record");
          if (ih.U32("ver") != 1) throw FormatError("index data version is not 1");
          conn = ih.U32("conn");
          count = ih.U32("count");
          const auto n = listed->second.find(conn);
          if (n == listed->second.end() || n->second != count)
            throw FormatError("disagrees with the index");
          if (static_cast<std::uint64_t>(count) * 12 != entries_size)
            throw FormatError("has a size that does not match its count");
          if (entries_offset + entries_size > index_pos) throw FormatError("runs into the index");
        } catch (const FormatError& e) {
          Fail(BagError::Kind::kCorrupt,
               "index data at " + At(at) + " after the chunk at " + At(offset) + ": " + e.what());
        }
        entries.resize(entries_size);
        ReadAt(entries_offset, entries_size, entries.data());
        ByteReader r(entries.data(), entries.size());
        for (std::uint32_t k = 0; k < count; ++k) {
          const std::uint32_t sec = r.U32(), nsec = r.U32(), in_chunk = r.U32();
          if (nsec > 999999999u || (sec == 0 && nsec == 0))
            Fail(BagError::Kind::kCorrupt, "index data at " + At(at) + " has an invalid time");
          if (static_cast<std::uint64_t>(in_chunk) + 8 > chunk.plain_size)
            Fail(BagError::Kind::kCorrupt, "index data at " + At(at) +
                                               " points outside the chunk at " + At(offset));
          if (chunk.compression == "none") CheckMessageRecord(offset, chunk, in_chunk, conn);
        }
        at = entries_offset + entries_size;
      }
      offset = at;
    }
    if (chunks != chunk_counts.size())
      Fail(BagError::Kind::kCorrupt, "has a damaged index: it lists " +
                                         std::to_string(chunk_counts.size()) +
                                         " chunks, the file holds " + std::to_string(chunks));
  }

  // The message record at offset in_chunk of an uncompressed chunk lies inside the chunk.
  void CheckMessageRecord(std::uint64_t chunk_pos, const ChunkHead& chunk, std::uint32_t in_chunk,
                          std::uint32_t conn) const {
    auto fail = [&](const std::string& what) {
      Fail(BagError::Kind::kCorrupt, "chunk at " + At(chunk_pos) + ": record at offset " +
                                         std::to_string(in_chunk) + " " + what);
    };
    const std::uint64_t size = chunk.plain_size;
    std::uint8_t b4[4];
    ReadAt(chunk.data_offset + in_chunk, 4, b4);
    const std::uint32_t header_size = ByteReader(b4, 4).U32();
    if (header_size > kMaxRecordHeaderBytes || in_chunk + 8ull + header_size > size)
      fail("has a header that runs past the chunk");
    std::vector<std::uint8_t> h(header_size + 4);
    ReadAt(chunk.data_offset + in_chunk + 4, h.size(), h.data());
    try {
      const RecordHeader header(h.data(), header_size);
      if (header.Op() != kOpMessage || header.U32("conn") != conn)
        throw FormatError("is not the indexed message");
    } catch (const FormatError& e) {
      fail(e.what());
    }
    const std::uint32_t message_size = ByteReader(h.data() + header_size, 4).U32();
    if (in_chunk + 8ull + header_size + message_size > size) fail("runs past the chunk");
  }

  void ReadIndex(std::uint64_t index_pos, std::uint32_t conn_count, std::uint32_t chunk_count,
                 std::set<std::uint32_t>* index_conns,
                 std::map<std::uint64_t, std::map<std::uint32_t, std::uint32_t>>* chunk_counts) {
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
        h.Str("topic");
        const RecordHeader fields(data, data_size);
        index_conns->insert(h.U32("conn"));
        ++got_conns;
      } else if (op == kOpChunkInfo) {
        if (h.U32("ver") != 1) throw FormatError("chunk info version is not 1");
        const std::uint64_t pos = h.U64("chunk_pos");
        const std::uint32_t n = h.U32("count");
        h.U64("start_time");
        h.U64("end_time");
        if (pos < first_record || pos >= index_pos)
          throw FormatError("chunk position out of range");
        if (static_cast<std::uint64_t>(n) * 8 != data_size)
          throw FormatError("chunk info size does not match its count");
        ByteReader d(data, data_size);
        auto& counts = (*chunk_counts)[pos];
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
    for (const auto& [pos, counts] : *chunk_counts)
      for (const auto& entry : counts)
        if (!index_conns->count(entry.first))
          throw FormatError("index counts an unknown connection");
  }

  // Walks the top-level records without decompressing, to locate a truncation.
  void WalkRecords() const {
    std::uint64_t offset = first_record;
    while (offset < file_size) {
      std::uint64_t data_offset = 0;
      std::uint32_t data_size = 0;
      const RecordHeader h = ReadRecordHeader(offset, &data_offset, &data_size);
      if (data_offset + data_size > file_size) {
        bool chunk = false;
        try {
          chunk = h.Op() == kOpChunk;
        } catch (const FormatError&) {
        }
        Fail(BagError::Kind::kTruncated,
             std::string("truncated: ends in the middle of ") +
                 (chunk ? "the chunk" : "the record") + " at " + At(offset) + " (" +
                 std::to_string(file_size - data_offset) + " of " + std::to_string(data_size) +
                 " bytes present)");
      }
      offset = data_offset + data_size;
    }
  }

  // ------------------------------------------------------------ rosbag path

  static bool IsDepthImage(const TopicParts& t) {
    return t.stream_type == "Depth" && t.rest == "image/data";
  }

  static bool IsMetadata(const std::string& topic, const TopicParts& t) {
    if (t.device >= 0 && t.sensor < 0)
      return topic == "/device_" + std::to_string(t.device) + "/info";
    if (t.sensor >= 0 && !t.option.empty()) return t.rest == "value" || t.rest == "description";
    return t.sensor >= 0 && (t.rest == "info" || t.rest == "info/camera_info");
  }

  // The serialized bytes of one message into `bytes`.
  void ReadMessage(const rosbag::MessageInstance& m) {
    ByteSink sink{&bytes};
    bytes.clear();
    m.write(sink);
  }

  void OpenWithRosbag() {
    // rosbag and ros::Header report some errors on the console before throwing; the library
    // does not print (the exception carries the error).
    console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_NONE);
    bool first_seen = false;
    std::string where = "opening it with rosbag";
    try {
      bag = std::make_unique<bag_detail::GuardedBag>();
      bag->Open(path, rosbag::bagmode::Read);
      where = "reading its index with rosbag";
      rosbag::View all(**bag);
      for (const rosbag::ConnectionInfo* c : all.getConnections()) {
        Connection& conn = conns[c->id];
        conn.topic = c->topic;
        conn.parts = ParseTopic(c->topic);
      }
      for (auto& [id, conn] : conns) {
        const std::uint32_t want = id;
        rosbag::View one(**bag, [want](const rosbag::ConnectionInfo* c) { return c->id == want; });
        conn.messages = one.size();
      }
      ChooseDepth();
      ros::Time first_time = ros::TIME_MAX;
      if (has_depth) {
        const std::uint32_t want = depth_conn;
        frames = std::make_unique<rosbag::View>(
            **bag, [want](const rosbag::ConnectionInfo* c) { return c->id == want; });
        rosbag::View::iterator it = frames->begin();
        if (it != frames->end()) {
          where = "reading its first depth frame";
          first_time = it->getTime();
          ReadMessage(*it);
          FirstFrame(bytes.data(), bytes.size());
          first_seen = true;
          rosbag::View::iterator last = it;
          for (++it; it != frames->end(); ++it) last = it;
          where = "reading its last depth frame";
          ReadMessage(*last);
          std::uint32_t seq = 0;
          DecodeStamp(bytes.data(), bytes.size(), &seq, &info.last_timestamp_ms);
        }
      }
      // Device and sensor info, options, stream info and camera_info recorded up to the first
      // depth frame.
      where = "reading its recorded options and stream info";
      const auto is_metadata = [](const rosbag::ConnectionInfo* c) {
        return IsMetadata(c->topic, ParseTopic(c->topic));
      };
      rosbag::View metadata(**bag, is_metadata, ros::TIME_MIN, first_time);
      for (const rosbag::MessageInstance& m : metadata) {
        where = "reading " + m.getTopic();
        ReadMessage(m);
        ProcessMetadata(m.getTopic(), ParseTopic(m.getTopic()), bytes.data(), bytes.size());
      }
    } catch (const FormatError& e) {
      Fail(BagError::Kind::kCorrupt, where + ": " + e.what());
    } catch (const ros::Exception& e) {  // rosbag::BagException and roscpp_serialization's
      Fail(BagError::Kind::kCorrupt, where + ": " + e.what());
    } catch (const std::bad_alloc&) {
      Fail(BagError::Kind::kCorrupt, where + ": out of memory");
    }
    BuildInfo(first_seen);
    if (frames) next_frame = frames->begin();
  }

  bool NextWithRosbag(records::DepthFrame* frame) {
    if (!frames || next_frame == frames->end()) return false;
    const std::string where = "depth frame " + std::to_string(frames_read + 1) + " of " +
                              std::to_string(info.depth_frames);
    struct Decoder : DepthDecoder {
      const Impl* impl;
      const std::string* where;
      records::DepthFrame* frame;
      Decoder(const Impl* i, const std::string* w, records::DepthFrame* f)
          : impl(i), where(w), frame(f) {}
      void Decode(const std::uint8_t* data, std::size_t size) override {
        impl->DecodeDepth(data, size, *where, frame);
      }
    } decoder(this, &where, frame);
    tl_depth_decoder = &decoder;
    try {
      if (!next_frame->instantiate<DepthImageBytes>())
        Fail(BagError::Kind::kCorrupt, where + ": is a " + next_frame->getDataType() +
                                           " message, not a sensor_msgs/Image");
    } catch (const ros::Exception& e) {  // rosbag::BagException and roscpp_serialization's
      tl_depth_decoder = nullptr;
      Fail(BagError::Kind::kCorrupt, where + ": " + e.what());
    } catch (...) {
      tl_depth_decoder = nullptr;
      throw;
    }
    tl_depth_decoder = nullptr;
    ++next_frame;
    ++frames_read;
    return true;
  }

  // ------------------------------------------------------------ partial path

  void OpenPartial() {
    partial = true;
    info.indexed = false;
    Scan();
    cursor = Cursor();
    cursor.next_record = first_record;
  }

  // Loads the next chunk at or after c->next_record. False at the end of the file.
  bool LoadNextChunk(Cursor* c) {
    while (c->next_record < file_size) {
      const std::uint64_t offset = c->next_record;
      std::uint64_t data_offset = 0;
      std::uint32_t data_size = 0;
      const RecordHeader h = ReadRecordHeader(offset, &data_offset, &data_size);
      std::uint8_t op = 0;
      try {
        op = h.Op();
      } catch (const FormatError& e) {
        Fail(BagError::Kind::kCorrupt, "record at " + At(offset) + ": " + e.what());
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
      const ChunkHead k = CheckChunk(offset, h, data_offset, data_size, true);
      const std::size_t stored = cut ? static_cast<std::size_t>(file_size - data_offset)
                                     : static_cast<std::size_t>(data_size);
      if (k.compression == "none") {
        if (c->data.size() < stored) c->data.resize(stored);
        ReadAt(data_offset, stored, c->data.data());
        c->size = stored;
      } else {
        if (c->raw.size() < stored) c->raw.resize(stored);
        ReadAt(data_offset, stored, c->raw.data());
        if (c->data.size() < k.plain_size) c->data.resize(k.plain_size);
        unsigned int out_size = k.plain_size;
        char* in = reinterpret_cast<char*>(c->raw.data());
        char* out = reinterpret_cast<char*>(c->data.data());
        const unsigned int in_size = static_cast<unsigned int>(stored);
        const bool ok =
            k.compression == "lz4"
                ? roslz4_buffToBuffDecompress(in, in_size, out, &out_size) == ROSLZ4_OK
                : BZ2_bzBuffToBuffDecompress(out, &out_size, in, in_size, 0, 0) == BZ_OK;
        if (!ok || out_size != k.plain_size)
          Fail(BagError::Kind::kCorrupt, k.compression + " chunk at " + At(offset) +
                                             " does not decompress (damaged data)");
        c->size = k.plain_size;
        info.compressed = true;
      }
      c->chunk_pos = offset;
      c->pos = 0;
      c->cut = cut;
      c->loaded = true;
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
      std::uint32_t data_size = 0;
      const std::uint8_t* data = nullptr;
      std::uint8_t op = 0;
      std::uint32_t conn = 0;
      try {
        const std::uint32_t header_size = r.U32();
        const RecordHeader h(r.Bytes(header_size), header_size);
        data_size = r.U32();
        data = r.Bytes(data_size);
        op = h.Op();
        if (op != kOpMessage && op != kOpConnection)
          throw FormatError("unexpected record op " + std::to_string(op));
        conn = h.U32("conn");
        if (op == kOpConnection && !conns.count(conn)) {
          Connection& added = conns[conn];
          added.topic = h.Str("topic");
          added.parts = ParseTopic(added.topic);
        }
      } catch (const FormatError& e) {
        damaged(std::string("record at offset ") + std::to_string(c->pos) + ": " + e.what());
      }
      c->pos += r.pos();
      if (op == kOpConnection) continue;
      if (!conns.count(conn)) damaged("message on unknown connection " + std::to_string(conn));
      *m = {conn, data, data_size};
      return true;
    }
    c->loaded = false;
    if (c->cut) damaged("file ends");
    return false;
  }

  bool NextMessage(Cursor* c, Message* m) {
    for (;;) {
      if (c->loaded && NextInChunk(c, m)) return true;
      if (!LoadNextChunk(c)) return false;
    }
  }

  // Reads the whole file up to the damage: counts messages, finds the depth stream, reads the
  // metadata recorded before its first frame and that frame's and the last frame's header.
  void Scan() {
    Cursor c;
    c.next_record = first_record;
    Message m;
    bool first_seen = false;
    try {
      while (NextMessage(&c, &m)) {
        Connection& conn = conns[m.conn];
        ++conn.messages;
        if (!has_depth) ChooseDepth();
        if (has_depth && m.conn == depth_conn) {
          try {
            if (!first_seen) {
              FirstFrame(m.data, m.size);
              first_seen = true;
            } else {
              std::uint32_t seq;
              DecodeStamp(m.data, m.size, &seq, &info.last_timestamp_ms);
            }
          } catch (const FormatError& e) {
            Fail(BagError::Kind::kCorrupt, std::string("depth frame: ") + e.what());
          }
        } else if (!first_seen && IsMetadata(conn.topic, conn.parts)) {
          try {
            ProcessMetadata(conn.topic, conn.parts, m.data, m.size);
          } catch (const FormatError& e) {
            Fail(BagError::Kind::kCorrupt, "message on " + conn.topic + ": " + e.what());
          }
        }
      }
    } catch (const BagError& e) {
      damage = e.what();
      ChooseDepth();
      if (!has_depth) throw;  // nothing readable before the damage
    }
    BuildInfo(first_seen);
  }

  bool NextPartial(records::DepthFrame* frame) {
    Message m;
    while (NextMessage(&cursor, &m)) {
      if (m.conn != depth_conn) continue;
      DecodeDepth(m.data, m.size, "depth frame in chunk at " + At(cursor.chunk_pos), frame);
      return true;
    }
    return false;
  }

  // ------------------------------------------------------------ shared by both paths

  void ChooseDepth() {
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

  void ProcessMetadata(const std::string& topic, const TopicParts& t, const std::uint8_t* data,
                       std::size_t size) {
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

  void FirstFrame(const std::uint8_t* data, std::size_t size) {
    const ImageView v = DecodeImage(data, size);
    info.first_timestamp_ms = info.last_timestamp_ms = v.stamp_ms;
    info.depth.encoding = v.encoding;  // the frames' own encoding wins over the stream info
    info.depth.width = static_cast<int>(v.width);
    info.depth.height = static_cast<int>(v.height);
    first_frame_has_units = v.has_depth_units;
    if (first_frame_has_units) info.depth_units_m = CheckedUnits(v);
  }

  void BuildInfo(bool first_seen) {
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
  double CheckedUnits(const ImageView& v) const {
    const std::string why = rules::kDepthUnitsM.Why(v.depth_units);
    if (!why.empty())
      Fail(BagError::Kind::kCorrupt,
           "depth frame " + std::to_string(v.seq) + ": depth units " + why);
    return v.depth_units;
  }

  // One serialized sensor_msgs/Image of the depth stream into a frame (both paths).
  void DecodeDepth(const std::uint8_t* data, std::size_t size, const std::string& where,
                   records::DepthFrame* frame) const {
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
};

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
