// BagReader's reads of a bag's records without rosbag (bag_reader.cpp says how the reader
// works): the structural check made before a file is handed to rosbag, and the partial path,
// which reads a bag rosbag cannot open by scanning its chunks in order up to the damage.

#include <bzlib.h>
#include <roslz4/lz4s.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "io/bag.h"
#include "io/bag_reader_impl.h"
#include "io/bag_records.h"

namespace depthbias::io {
namespace {

using namespace bag_detail;

constexpr std::uint32_t kMaxRecordHeaderBytes = 1u << 20;  // real headers hold a few fields
constexpr std::uint64_t kMaxIndexBytes = 1ull << 30;

}  // namespace

void BagReader::Impl::ReadAt(std::uint64_t offset, std::size_t count, std::uint8_t* dst) const {
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
RecordHeader BagReader::Impl::ReadRecordHeader(std::uint64_t offset, std::uint64_t* data_offset,
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
BagReader::Impl::ChunkHead BagReader::Impl::CheckChunk(std::uint64_t offset, const RecordHeader& h,
                                                       std::uint64_t data_offset,
                                                       std::uint32_t data_size,
                                                       bool allow_cut) const {
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

// ------------------------------------------------------------ structural check

// Everything rosbag::Bag reads without checking: the index (connections, chunk infos), every
// chunk's header and the index data after it, and, in uncompressed chunks, the record of every
// indexed message. Nothing is decompressed. Throws BagError.
void BagReader::Impl::CheckStructure(std::uint64_t index_pos, std::uint32_t conn_count,
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
void BagReader::Impl::CheckMessageRecord(std::uint64_t chunk_pos, const ChunkHead& chunk,
                                         std::uint32_t in_chunk, std::uint32_t conn) const {
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

void BagReader::Impl::ReadIndex(
    std::uint64_t index_pos, std::uint32_t conn_count, std::uint32_t chunk_count,
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
void BagReader::Impl::WalkRecords() const {
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

// ------------------------------------------------------------ partial path

void BagReader::Impl::OpenPartial() {
  partial = true;
  info.indexed = false;
  Scan();
  cursor = Cursor();
  cursor.next_record = first_record;
}

// Loads the next chunk at or after c->next_record. False at the end of the file.
bool BagReader::Impl::LoadNextChunk(Cursor* c) {
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
bool BagReader::Impl::NextInChunk(Cursor* c, Message* m) {
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

bool BagReader::Impl::NextMessage(Cursor* c, Message* m) {
  for (;;) {
    if (c->loaded && NextInChunk(c, m)) return true;
    if (!LoadNextChunk(c)) return false;
  }
}

// Reads the whole file up to the damage: counts messages, finds the depth stream, reads the
// metadata recorded before its first frame and that frame's and the last frame's header.
void BagReader::Impl::Scan() {
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

bool BagReader::Impl::NextPartial(records::DepthFrame* frame) {
  Message m;
  while (NextMessage(&cursor, &m)) {
    if (m.conn != depth_conn) continue;
    DecodeDepth(m.data, m.size, "depth frame in chunk at " + At(cursor.chunk_pos), frame);
    return true;
  }
  return false;
}

}  // namespace depthbias::io
