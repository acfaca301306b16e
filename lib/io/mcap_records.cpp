#include "io/mcap_records.h"

#include "io/byte_cursor.h"

namespace depthbias::io::mcap {
namespace {

std::string Str(ByteCursor* c) { return c->String(c->U32()); }

// A map<string, string> field: uint32 byte length, then key/value strings within it.
bool StringMap(ByteCursor* c, std::map<std::string, std::string>* out) {
  const std::uint32_t len = c->U32();
  if (!c->ok() || len > c->left()) return false;
  ByteCursor m(c->here(), len);
  while (m.ok() && m.left() > 0) {
    std::string key = Str(&m);
    std::string value = Str(&m);
    if (m.ok()) (*out)[key] = value;
  }
  c->Skip(len);
  return m.ok() && c->ok();
}

// A map<uint16, uint64> field: uint32 byte length, then 10-byte entries.
bool IdMap(ByteCursor* c, std::map<std::uint16_t, std::uint64_t>* out) {
  const std::uint32_t len = c->U32();
  if (!c->ok() || len > c->left() || len % 10 != 0) return false;
  for (std::uint32_t i = 0; i < len / 10; ++i) {
    const std::uint16_t id = c->U16();
    (*out)[id] = c->U64();
  }
  return c->ok();
}

}  // namespace

bool ParseHeader(const std::uint8_t* p, std::size_t n, Header* out) {
  ByteCursor c(p, n);
  out->profile = Str(&c);
  out->library = Str(&c);
  return c.ok();
}

bool ParseFooter(const std::uint8_t* p, std::size_t n, Footer* out) {
  ByteCursor c(p, n);
  out->summary_start = c.U64();
  out->summary_offset_start = c.U64();
  out->summary_crc = c.U32();
  return c.ok();
}

bool ParseSchema(const std::uint8_t* p, std::size_t n, Schema* out) {
  ByteCursor c(p, n);
  out->id = c.U16();
  out->name = Str(&c);
  out->encoding = Str(&c);
  out->data = Str(&c);
  return c.ok();
}

bool ParseChannel(const std::uint8_t* p, std::size_t n, Channel* out) {
  ByteCursor c(p, n);
  out->id = c.U16();
  out->schema_id = c.U16();
  out->topic = Str(&c);
  out->message_encoding = Str(&c);
  return c.ok() && StringMap(&c, &out->metadata);
}

bool ParseMessage(const std::uint8_t* p, std::size_t n, Message* out) {
  ByteCursor c(p, n);
  out->channel_id = c.U16();
  out->sequence = c.U32();
  out->log_time_ns = c.U64();
  out->publish_time_ns = c.U64();
  if (!c.ok()) return false;
  out->data = c.here();
  out->size = c.left();
  return true;
}

bool ParseChunk(const std::uint8_t* p, std::size_t n, Chunk* out) {
  ByteCursor c(p, n);
  out->message_start_time = c.U64();
  out->message_end_time = c.U64();
  out->uncompressed_size = c.U64();
  out->uncompressed_crc = c.U32();
  out->compression = Str(&c);
  out->compressed_size = c.U64();
  out->records = c.Bytes(out->compressed_size);
  return c.ok();
}

bool ParseChunkIndex(const std::uint8_t* p, std::size_t n, ChunkIndex* out) {
  ByteCursor c(p, n);
  out->message_start_time = c.U64();
  out->message_end_time = c.U64();
  out->chunk_start_offset = c.U64();
  out->chunk_length = c.U64();
  if (!IdMap(&c, &out->message_index_offsets)) return false;
  out->message_index_length = c.U64();
  out->compression = Str(&c);
  out->compressed_size = c.U64();
  out->uncompressed_size = c.U64();
  return c.ok();
}

bool ParseStatistics(const std::uint8_t* p, std::size_t n, Statistics* out) {
  ByteCursor c(p, n);
  out->message_count = c.U64();
  c.U16();  // schema count
  c.U32();  // channel count
  c.U32();  // attachment count
  c.U32();  // metadata count
  out->chunk_count = c.U32();
  out->message_start_time = c.U64();
  out->message_end_time = c.U64();
  return c.ok() && IdMap(&c, &out->channel_message_counts);
}

void PutU16(std::string* out, std::uint16_t v) {
  for (int i = 0; i < 2; ++i) out->push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}
void PutU32(std::string* out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out->push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}
void PutU64(std::string* out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out->push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}
void PutString(std::string* out, const std::string& s) {
  PutU32(out, static_cast<std::uint32_t>(s.size()));
  out->append(s);
}
void PutRecord(std::string* out, Opcode op, const std::string& content) {
  out->push_back(static_cast<char>(op));
  PutU64(out, content.size());
  out->append(content);
}

}  // namespace depthbias::io::mcap
