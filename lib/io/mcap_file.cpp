#include "io/mcap_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <future>
#include <cerrno>
#include <cstring>

#include "io/byte_cursor.h"
#include "io/chunk_compression.h"

namespace depthbias::io {

struct McapFile::Walk {
  std::uint64_t offset = 0;  // next top-level record
  bool in_chunk = false;
  const std::uint8_t* records = nullptr;
  std::size_t size = 0;
  std::size_t pos = 0;
  std::uint64_t chunk_offset = 0;
  std::uint64_t record_offset = 0;  // the top-level record being read
};

namespace {

std::string At(std::uint64_t offset) { return "byte " + std::to_string(offset); }

std::uint64_t Le64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

bool Overlaps(const std::set<std::uint16_t>& a, const std::set<std::uint16_t>& b) {
  for (std::uint16_t id : a)
    if (b.count(id)) return true;
  return false;
}

}  // namespace

void McapFile::Fail(BagError::Kind kind, const std::string& what) const {
  throw BagError(kind, path_, what);
}

McapFile::McapFile(const std::string& path) : path_(path), walk_(std::make_unique<Walk>()) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    Fail(errno == ENOENT ? BagError::Kind::kNotFound : BagError::Kind::kNotAFile,
         std::strerror(errno));
  if (!S_ISREG(st.st_mode)) Fail(BagError::Kind::kNotAFile, "not a regular file");
  if (st.st_size == 0) Fail(BagError::Kind::kEmpty, "empty file");
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) Fail(BagError::Kind::kNotFound, std::strerror(errno));
  size_ = static_cast<std::uint64_t>(st.st_size);
  std::uint8_t magic[8];
  if (size_ < 8 || ::pread(fd_, magic, 8, 0) != 8 || std::memcmp(magic, mcap::kMagic, 8) != 0) {
    ::close(fd_);
    fd_ = -1;
    Fail(BagError::Kind::kNotABag, "not an MCAP file (no MCAP magic at its start)");
  }
  try {
    std::uint8_t op = 0;
    std::string why;
    if (!ReadRecord(8, size_, &op, &record_, &why))
      Fail(BagError::Kind::kTruncated, "cut short in its header record: " + why);
    if (op != mcap::kHeader || !mcap::ParseHeader(record_.data(), record_.size(),
                                                  &contents_.header))
      Fail(BagError::Kind::kCorrupt, "no valid header record after the magic");
    data_start_ = 8 + mcap::kRecordPrefix + record_.size();
    const std::uint64_t tail = mcap::kRecordPrefix + mcap::kFooterContent + 8;
    bool closed = false;
    if (size_ >= data_start_ + tail) {
      std::uint8_t end[8];
      closed = ::pread(fd_, end, 8, static_cast<off_t>(size_ - 8)) == 8 &&
               std::memcmp(end, mcap::kMagic, 8) == 0;
    }
    if (!closed) {
      data_end_ = size_;
      Scan();
      if (contents_.damage.empty())
        contents_.damage = "no footer: the file was not closed (cut short?)";
      return;
    }
    const std::uint64_t footer_at = size_ - tail;
    if (!ReadRecord(footer_at, size_ - 8, &op, &record_, &why) || op != mcap::kFooter)
      Fail(BagError::Kind::kCorrupt, "no footer record before the closing magic");
    mcap::Footer footer;
    if (!mcap::ParseFooter(record_.data(), record_.size(), &footer))
      Fail(BagError::Kind::kCorrupt, "footer record too short");
    data_end_ = footer_at;
    if (footer.summary_start == 0) {
      Scan();
      return;
    }
    const std::uint64_t summary_end =
        footer.summary_offset_start ? footer.summary_offset_start : footer_at;
    if (footer.summary_start < data_start_ || footer.summary_start > summary_end ||
        summary_end > footer_at)
      Fail(BagError::Kind::kCorrupt, "footer points its summary section outside the file (" +
                                         At(footer.summary_start) + ")");
    data_end_ = footer.summary_start;
    ReadSummary(footer.summary_start, summary_end);
    Rewind();
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
  }
}

McapFile::~McapFile() {
  ahead_.clear();  // waits for the chunks still decompressing
  if (fd_ >= 0) ::close(fd_);
}

bool McapFile::ReadRecord(std::uint64_t offset, std::uint64_t limit, std::uint8_t* op,
                          McapBytes* content, std::string* why) const {
  std::uint8_t prefix[mcap::kRecordPrefix];
  if (offset > limit || limit - offset < mcap::kRecordPrefix ||
      ::pread(fd_, prefix, sizeof prefix, static_cast<off_t>(offset)) !=
          static_cast<ssize_t>(sizeof prefix)) {
    *why = "ends inside a record's header at " + At(offset);
    return false;
  }
  *op = prefix[0];
  const std::uint64_t len = Le64(prefix + 1);
  const std::uint64_t left = limit - offset - mcap::kRecordPrefix;
  if (len > left) {
    *why = "record at " + At(offset) + " (opcode " + std::to_string(*op) + ") claims " +
           std::to_string(len) + " bytes, " + std::to_string(left) + " left";
    return false;
  }
  if (!content) return true;
  content->resize(static_cast<std::size_t>(len));
  std::size_t got = 0;
  while (got < len) {
    const ssize_t n = ::pread(fd_, content->data() + got, static_cast<std::size_t>(len) - got,
                              static_cast<off_t>(offset + mcap::kRecordPrefix + got));
    if (n <= 0) {
      *why = "cannot read " + At(offset + got) + ": " + (n < 0 ? std::strerror(errno) : "EOF");
      return false;
    }
    got += static_cast<std::size_t>(n);
  }
  return true;
}

std::shared_ptr<McapFile::Loaded> McapFile::LoadAt(std::uint64_t at) const {
  auto out = std::make_shared<Loaded>();
  std::uint8_t op = 0;
  mcap::Chunk chunk;
  if (!ReadRecord(at, data_end_, &op, &out->raw, &out->error)) {
    out->kind = BagError::Kind::kTruncated;
    return out;
  }
  if (!mcap::ParseChunk(out->raw.data(), out->raw.size(), &chunk)) {
    out->error = "chunk at " + At(at) + " is shorter than its fields say";
    return out;
  }
  out->compression = chunk.compression.empty() ? "none" : chunk.compression;
  const std::uint64_t cap =
      std::min(kMaxChunkBytes, std::max(kMinChunkCap, kMaxChunkRatio * size_));
  const std::size_t n = static_cast<std::size_t>(chunk.uncompressed_size);
  std::string why;
  const std::uint8_t* records = chunk.records;
  if (chunk.uncompressed_size > cap) {
    why = "a chunk claims " + std::to_string(chunk.uncompressed_size) +
          " bytes uncompressed, more than the reader's limit of " + std::to_string(cap);
  } else if (chunk.compression.empty()) {
    if (chunk.compressed_size != chunk.uncompressed_size)
      why = "an uncompressed chunk of " + std::to_string(chunk.compressed_size) +
            " bytes claims " + std::to_string(chunk.uncompressed_size);
  } else {
    out->plain.resize(n);
    why = DecompressChunk(chunk.compression, chunk.records,
                          static_cast<std::size_t>(chunk.compressed_size), out->plain.data(), n);
    records = out->plain.data();
  }
  if (why.empty() && chunk.uncompressed_crc != 0 && Crc32(records, n) != chunk.uncompressed_crc)
    why = "a chunk's CRC does not match its records";
  if (!why.empty()) {
    out->error = "chunk at " + At(at) + ": " + why;
    return out;
  }
  out->records = records;
  out->size = n;
  return out;
}

std::shared_ptr<McapFile::Loaded> McapFile::Chunk(std::uint64_t at,
                                                   const std::set<std::uint16_t>& wanted) {
  if (scan_pass_ || order_.empty()) return LoadAt(at);
  // Chunks the index says hold a wanted channel, up to kChunksAhead decompressing at once
  // (the one needed now among them), each on its own thread.
  for (auto it = ahead_.begin(); it != ahead_.end() && it->first < at;) it = ahead_.erase(it);
  auto next = std::lower_bound(order_.begin(), order_.end(), at);
  for (; next != order_.end() && ahead_.size() < kChunksAhead; ++next) {
    const auto ids = chunk_channels_.find(*next);
    if (*next != at && ids != chunk_channels_.end() && !Overlaps(ids->second, wanted)) continue;
    if (!ahead_.count(*next))
      ahead_[*next] = std::async(std::launch::async, [this, off = *next] { return LoadAt(off); });
  }
  const auto it = ahead_.find(at);
  if (it == ahead_.end()) return LoadAt(at);  // more than kChunksAhead ahead of the walk
  std::shared_ptr<Loaded> loaded = it->second.get();
  ahead_.erase(it);
  return loaded;
}

void McapFile::ReadSummary(std::uint64_t start, std::uint64_t end) {
  bool statistics = false;
  for (std::uint64_t at = start; at < end;) {
    std::uint8_t op = 0;
    std::string why;
    if (!ReadRecord(at, end, &op, &record_, &why))
      Fail(BagError::Kind::kCorrupt, "summary section: " + why);
    const std::uint8_t* p = record_.data();
    const std::size_t n = record_.size();
    bool ok = true;
    if (op == mcap::kSchema) {
      mcap::Schema s;
      if ((ok = mcap::ParseSchema(p, n, &s))) Note(s);
    } else if (op == mcap::kChannel) {
      mcap::Channel c;
      if ((ok = mcap::ParseChannel(p, n, &c))) Note(c);
    } else if (op == mcap::kChunkIndex) {
      mcap::ChunkIndex ci;
      ok = mcap::ParseChunkIndex(p, n, &ci) && ci.chunk_start_offset >= data_start_ &&
           ci.chunk_start_offset < data_end_;
      if (ok) {
        ++contents_.chunks;
        contents_.compressions.insert(ci.compression.empty() ? "none" : ci.compression);
        std::set<std::uint16_t>& ids = chunk_channels_[ci.chunk_start_offset];
        for (const auto& kv : ci.message_index_offsets) ids.insert(kv.first);
        if (ids.empty()) chunk_channels_.erase(ci.chunk_start_offset);  // unknown: read it
      }
    } else if (op == mcap::kStatistics) {
      mcap::Statistics s;
      if ((ok = mcap::ParseStatistics(p, n, &s))) {
        statistics = true;
        contents_.message_counts = s.channel_message_counts;
        contents_.message_start_ns = s.message_start_time;
        contents_.message_end_ns = s.message_end_time;
      }
    }
    if (!ok)
      Fail(BagError::Kind::kCorrupt, "summary section: record at " + At(at) + " (opcode " +
                                         std::to_string(op) + ") cannot be decoded");
    at += mcap::kRecordPrefix + n;
  }
  contents_.summary = true;
  for (const auto& kv : chunk_channels_) order_.push_back(kv.first);  // sorted by offset
  if (!statistics) {  // counts and times only from the records themselves
    chunk_channels_.clear();
    order_.clear();
    contents_.chunks = 0;
    contents_.compressions.clear();
    Scan();
  }
}

void McapFile::Scan() {
  scan_pass_ = true;
  const std::uint64_t limit = data_end_;
  for (int attempt = 0; attempt < 2; ++attempt) {
    contents_.message_counts.clear();
    contents_.message_start_ns = ~0ull;
    contents_.message_end_ns = 0;
    contents_.chunks = 0;
    contents_.compressions.clear();
    Rewind();
    mcap::Message m;
    try {
      while (Next({}, &m)) {
        ++contents_.message_counts[m.channel_id];
        contents_.message_start_ns = std::min(contents_.message_start_ns, m.log_time_ns);
        contents_.message_end_ns = std::max(contents_.message_end_ns, m.log_time_ns);
      }
      data_end_ = std::min(limit, walk_->offset);
      break;
    } catch (const BagError& e) {
      // A scanned file is read up to its first damage: the records before it are kept, and the
      // second pass counts only those.
      const std::string what = e.what();
      contents_.damage = what.substr(std::min(what.size(), path_.size() + 2));
      data_end_ = walk_->record_offset;
    }
  }
  scan_pass_ = false;
  if (contents_.message_start_ns > contents_.message_end_ns) contents_.message_start_ns = 0;
  Rewind();
}

void McapFile::Rewind() {
  ahead_.clear();
  current_.reset();
  *walk_ = Walk();
  walk_->offset = data_start_;
}

bool McapFile::Next(const std::set<std::uint16_t>& wanted, mcap::Message* msg) {
  Walk& w = *walk_;
  const bool scanning = !contents_.summary || chunk_channels_.empty();
  while (true) {
    while (w.in_chunk) {
      if (w.pos == w.size) {
        w.in_chunk = false;
        break;
      }
      ByteCursor c(w.records + w.pos, w.size - w.pos);
      const std::uint8_t op = c.U8();
      const std::uint64_t len = c.U64();
      if (!c.ok() || len > c.left())
        Fail(BagError::Kind::kCorrupt, "chunk at " + At(w.chunk_offset) +
                                           ": a record runs past the chunk's end");
      const std::uint8_t* p = c.here();
      const std::size_t n = static_cast<std::size_t>(len);
      w.pos += mcap::kRecordPrefix + n;
      if (op == mcap::kMessage) {
        if (!mcap::ParseMessage(p, n, msg))
          Fail(BagError::Kind::kCorrupt, "chunk at " + At(w.chunk_offset) + ": short message");
        if (scan_pass_ || wanted.count(msg->channel_id)) return true;
      } else if (op == mcap::kSchema && scanning) {
        mcap::Schema s;
        if (!mcap::ParseSchema(p, n, &s))
          Fail(BagError::Kind::kCorrupt, "chunk at " + At(w.chunk_offset) + ": bad schema");
        Note(s);
      } else if (op == mcap::kChannel && scanning) {
        mcap::Channel ch;
        if (!mcap::ParseChannel(p, n, &ch))
          Fail(BagError::Kind::kCorrupt, "chunk at " + At(w.chunk_offset) + ": bad channel");
        Note(ch);
      }
    }
    if (w.offset >= data_end_) return false;
    std::uint8_t op = 0;
    std::string why;
    w.record_offset = w.offset;
    if (!ReadRecord(w.offset, data_end_, &op, nullptr, &why))
      Fail(contents_.summary ? BagError::Kind::kCorrupt : BagError::Kind::kTruncated, why);
    const std::uint64_t at = w.offset;
    w.record_offset = at;
    std::uint8_t prefix[mcap::kRecordPrefix];
    if (::pread(fd_, prefix, sizeof prefix, static_cast<off_t>(at)) != sizeof(prefix))
      Fail(BagError::Kind::kTruncated, "cannot read " + At(at));
    const std::uint64_t len = Le64(prefix + 1);
    w.offset = at + mcap::kRecordPrefix + len;
    if (op == mcap::kDataEnd || op == mcap::kFooter) {
      w.offset = data_end_;
      return false;
    }
    const auto known = chunk_channels_.find(at);
    if (op == mcap::kChunk && !scan_pass_ && known != chunk_channels_.end() &&
        !Overlaps(known->second, wanted))
      continue;  // the chunk index says none of the wanted channels is in it
    if (op != mcap::kChunk && op != mcap::kMessage && op != mcap::kSchema &&
        op != mcap::kChannel)
      continue;
    if (op == mcap::kChunk) {
      w.chunk_offset = at;
      current_ = Chunk(at, wanted);
      if (!current_->error.empty()) Fail(current_->kind, current_->error);
      if (scan_pass_) {
        ++contents_.chunks;
        contents_.compressions.insert(current_->compression);
      }
      w.records = current_->records;
      w.size = current_->size;
      w.pos = 0;
      w.in_chunk = true;
      continue;
    }
    if (!ReadRecord(at, data_end_, &op, &record_, &why))
      Fail(BagError::Kind::kTruncated, why);
    if (op == mcap::kMessage) {
      if (!mcap::ParseMessage(record_.data(), record_.size(), msg))
        Fail(BagError::Kind::kCorrupt, "message at " + At(at) + " is too short");
      if (scan_pass_ || wanted.count(msg->channel_id)) return true;
    } else if (op == mcap::kSchema && scanning) {
      mcap::Schema s;
      if (!mcap::ParseSchema(record_.data(), record_.size(), &s))
        Fail(BagError::Kind::kCorrupt, "schema at " + At(at) + " cannot be decoded");
      Note(s);
    } else if (op == mcap::kChannel && scanning) {
      mcap::Channel ch;
      if (!mcap::ParseChannel(record_.data(), record_.size(), &ch))
        Fail(BagError::Kind::kCorrupt, "channel at " + At(at) + " cannot be decoded");
      Note(ch);
    }
  }
}

}  // namespace depthbias::io
