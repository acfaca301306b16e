#pragma once
// A bounded little-endian reader over bytes already in memory: every read checks what is left
// first, so a length field read from a file can never move it past the end. Used by the MCAP
// record parser and the CDR decoder (both little-endian on every recording ROS 2 writes).

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

namespace depthbias::io {

class ByteCursor {
 public:
  ByteCursor(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  std::size_t size() const { return size_; }
  std::size_t pos() const { return pos_; }
  std::size_t left() const { return size_ - pos_; }
  const std::uint8_t* here() const { return data_ + pos_; }
  bool ok() const { return ok_; }  // false once a read asked for more than was left

  // Each read returns 0 / empty and clears ok() when fewer bytes are left than it needs.
  std::uint8_t U8() { return static_cast<std::uint8_t>(Uint(1)); }
  std::uint16_t U16() { return static_cast<std::uint16_t>(Uint(2)); }
  std::uint32_t U32() { return static_cast<std::uint32_t>(Uint(4)); }
  std::uint64_t U64() { return Uint(8); }
  double F64() {
    const std::uint64_t bits = U64();
    double v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }
  float F32() {
    const std::uint32_t bits = U32();
    float v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }
  // n bytes as they are; nullptr when fewer are left.
  const std::uint8_t* Bytes(std::uint64_t n) {
    if (!ok_ || n > left()) {
      ok_ = false;
      return nullptr;
    }
    const std::uint8_t* p = data_ + pos_;
    pos_ += static_cast<std::size_t>(n);
    return p;
  }
  std::string String(std::uint64_t n) {
    const std::uint8_t* p = Bytes(n);
    return p ? std::string(reinterpret_cast<const char*>(p), static_cast<std::size_t>(n))
             : std::string();
  }
  bool Skip(std::uint64_t n) { return Bytes(n) != nullptr || n == 0; }
  // Moves to an absolute position within the bytes (false past the end).
  bool Seek(std::size_t pos) {
    if (pos > size_) return ok_ = false;
    pos_ = pos;
    return true;
  }

 private:
  std::uint64_t Uint(int n) {
    const std::uint8_t* p = Bytes(static_cast<std::uint64_t>(n));
    if (!p) return 0;
    std::uint64_t v = 0;
    for (int i = n - 1; i >= 0; --i) v = (v << 8) | p[i];
    return v;
  }

  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
  bool ok_ = true;
};

}  // namespace depthbias::io
