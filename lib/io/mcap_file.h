#pragma once
// An MCAP file's messages, read one at a time in file order (https://mcap.dev/spec). When the
// file ends with its footer and a summary section, the summary gives the channels, schemas,
// message counts and chunk indexes, and chunks that hold none of the wanted channels are skipped
// without being read. When the summary is missing (the writer crashed, or wrote none), the file
// is scanned once at open from its header: a file cut short gives every record before the cut,
// and damage() says where it ends. With chunk indexes, the next chunks holding a wanted channel
// are read and decompressed ahead on other threads (kChunksAhead at once, the walk's own among
// them): memory holds that many chunks, compressed and decompressed.
//
// Bounds: no length read from the file is trusted beyond what the file holds; a chunk's
// uncompressed size is at most kMaxChunkBytes and at most kMaxChunkRatio times the file's size
// (with a floor of kMinChunkCap), so a hostile file cannot make the reader allocate more.

#include <cstdint>
#include <future>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "io/bag.h"
#include "io/mcap_records.h"

namespace depthbias::io {

// Bytes that resize() leaves uninitialised: every chunk is overwritten by pread or the
// decompressor at once, and zero-filling 2 MB per frame first costs as much as a CRC.
template <typename T>
struct UninitAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = UninitAllocator<U>;
  };
  UninitAllocator() = default;
  template <typename U>
  UninitAllocator(const UninitAllocator<U>&) {}
  template <typename U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};
using McapBytes = std::vector<std::uint8_t, UninitAllocator<std::uint8_t>>;

struct McapContents {
  mcap::Header header;
  bool summary = false;  // the summary section was read (else the file was scanned)
  std::map<std::uint16_t, mcap::Schema> schemas;
  std::map<std::uint16_t, mcap::Channel> channels;
  std::map<std::uint16_t, std::uint64_t> message_counts;  // per channel
  std::uint64_t message_start_ns = 0;
  std::uint64_t message_end_ns = 0;
  std::uint64_t chunks = 0;
  std::set<std::string> compressions;  // of the chunks ("none" for uncompressed ones)
  std::string damage;                  // where a scanned file stops being readable; "" if whole
};

class McapFile {
 public:
  static constexpr std::uint64_t kMaxChunkBytes = 1ull << 30;
  static constexpr std::uint64_t kMaxChunkRatio = 64;
  static constexpr std::uint64_t kMinChunkCap = 64ull << 20;
  static constexpr std::size_t kChunksAhead = 2;  // chunks decompressing at once (indexed)

  // Opens the file, checks its magic and reads its summary or scans it. Throws BagError
  // naming the file (not an MCAP file, truncated before any record, corrupt summary, ...).
  explicit McapFile(const std::string& path);
  ~McapFile();
  McapFile(const McapFile&) = delete;
  McapFile& operator=(const McapFile&) = delete;

  const McapContents& contents() const { return contents_; }
  const std::string& path() const { return path_; }

  // Next message on a channel in wanted, in file order; false at the end of the readable data.
  // msg->data stays valid until the next call. Throws BagError on a corrupt record or chunk
  // (bad CRC, a frame that does not decompress, a length past the end of the data).
  bool Next(const std::set<std::uint16_t>& wanted, mcap::Message* msg);
  void Rewind();

 private:
  struct Walk;  // position of Next
  void ReadSummary(std::uint64_t summary_start, std::uint64_t summary_end);
  void Scan();  // no usable summary: channels, counts and the readable end from the records
  // Reads the record whose prefix is at offset; false (and *why) when it runs past limit.
  bool ReadRecord(std::uint64_t offset, std::uint64_t limit, std::uint8_t* op,
                  McapBytes* content, std::string* why) const;
  // One chunk read, decompressed and checked (its CRC), or why not; safe on any thread.
  struct Loaded {
    McapBytes raw, plain;
    const std::uint8_t* records = nullptr;
    std::size_t size = 0;
    std::string compression;  // "none", "zstd", "lz4"
    std::string error;        // "" when loaded
    BagError::Kind kind = BagError::Kind::kCorrupt;
  };
  std::shared_ptr<Loaded> LoadAt(std::uint64_t offset) const;
  // The chunk at offset for the walk: with chunk indexes, the next chunks holding a wanted
  // channel are decompressed ahead on other threads.
  std::shared_ptr<Loaded> Chunk(std::uint64_t offset, const std::set<std::uint16_t>& wanted);
  void Note(const mcap::Schema& s) { contents_.schemas[s.id] = s; }
  void Note(const mcap::Channel& c) { contents_.channels[c.id] = c; }
  [[noreturn]] void Fail(BagError::Kind kind, const std::string& what) const;

  std::string path_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
  std::uint64_t data_start_ = 0;
  std::uint64_t data_end_ = 0;  // end of the readable data section
  McapContents contents_;
  std::map<std::uint64_t, std::set<std::uint16_t>> chunk_channels_;  // by chunk start offset
  std::vector<std::uint64_t> order_;  // indexed chunks' offsets, ascending
  McapBytes record_;
  std::map<std::uint64_t, std::future<std::shared_ptr<Loaded>>> ahead_;
  std::shared_ptr<Loaded> current_;  // the chunk the walk is in
  std::unique_ptr<Walk> walk_;
  bool scan_pass_ = false;  // Scan's pass: every channel, chunks counted
};

}  // namespace depthbias::io
