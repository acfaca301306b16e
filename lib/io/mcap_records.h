#pragma once
// The records of an MCAP file (https://mcap.dev/spec, major version 0), parsed from bytes already
// in memory: each parser takes one record's content (what follows the opcode and the 8-byte
// length) and returns false when the content is shorter than its fields say or a nested length
// runs past it. Only the records a recording reader needs have a struct; the others are skipped
// by their length.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace depthbias::io::mcap {

// "\x89MCAP0\r\n": at the start and at the end of every MCAP file.
constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

constexpr std::size_t kRecordPrefix = 9;  // opcode (1) + content length (8)
constexpr std::size_t kFooterContent = 20;

struct Header {
  std::string profile;  // "ros2" for rosbag2
  std::string library;
};

struct Footer {
  std::uint64_t summary_start = 0;         // 0: no summary section
  std::uint64_t summary_offset_start = 0;  // 0: no summary offset section
  std::uint32_t summary_crc = 0;
};

struct Schema {
  std::uint16_t id = 0;
  std::string name;      // e.g. sensor_msgs/msg/Image
  std::string encoding;  // "ros2msg", "ros2idl", ...
  std::string data;
};

struct Channel {
  std::uint16_t id = 0;
  std::uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;  // "cdr" for ROS 2
  std::map<std::string, std::string> metadata;
};

// A Message's fields; data points into the bytes it was parsed from.
struct Message {
  std::uint16_t channel_id = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time_ns = 0;
  std::uint64_t publish_time_ns = 0;
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};

// A Chunk's fields; records points into the bytes it was parsed from.
struct Chunk {
  std::uint64_t message_start_time = 0;
  std::uint64_t message_end_time = 0;
  std::uint64_t uncompressed_size = 0;
  std::uint32_t uncompressed_crc = 0;  // 0: not computed by the writer
  std::string compression;             // "", "zstd" or "lz4"
  const std::uint8_t* records = nullptr;
  std::uint64_t compressed_size = 0;
};

struct ChunkIndex {
  std::uint64_t message_start_time = 0;
  std::uint64_t message_end_time = 0;
  std::uint64_t chunk_start_offset = 0;
  std::uint64_t chunk_length = 0;
  std::map<std::uint16_t, std::uint64_t> message_index_offsets;  // channel → offset
  std::uint64_t message_index_length = 0;
  std::string compression;
  std::uint64_t compressed_size = 0;
  std::uint64_t uncompressed_size = 0;
};

struct Statistics {
  std::uint64_t message_count = 0;
  std::uint32_t chunk_count = 0;
  std::uint64_t message_start_time = 0;
  std::uint64_t message_end_time = 0;
  std::map<std::uint16_t, std::uint64_t> channel_message_counts;
};

bool ParseHeader(const std::uint8_t* p, std::size_t n, Header* out);
bool ParseFooter(const std::uint8_t* p, std::size_t n, Footer* out);
bool ParseSchema(const std::uint8_t* p, std::size_t n, Schema* out);
bool ParseChannel(const std::uint8_t* p, std::size_t n, Channel* out);
bool ParseMessage(const std::uint8_t* p, std::size_t n, Message* out);
bool ParseChunk(const std::uint8_t* p, std::size_t n, Chunk* out);
bool ParseChunkIndex(const std::uint8_t* p, std::size_t n, ChunkIndex* out);
bool ParseStatistics(const std::uint8_t* p, std::size_t n, Statistics* out);

// Little-endian writers of the same fields (the MCAP writer's side).
void PutU16(std::string* out, std::uint16_t v);
void PutU32(std::string* out, std::uint32_t v);
void PutU64(std::string* out, std::uint64_t v);
void PutString(std::string* out, const std::string& s);  // uint32 length + bytes
// opcode + uint64 content length + content.
void PutRecord(std::string* out, Opcode op, const std::string& content);

}  // namespace depthbias::io::mcap
