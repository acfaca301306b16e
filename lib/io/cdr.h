#pragma once
// The CDR encoding ROS 2 serializes its messages in (OMG XCDR version 1, "plain CDR", as
// rmw_fastrtps and rmw_cyclonedds write it; rosbag2 stores exactly those bytes): a 4-byte
// encapsulation header (0x00 0x01 for little-endian CDR) and then the fields, each primitive
// aligned to its own size counted from the end of the header, strings as a uint32 length that
// counts the closing NUL, sequences as a uint32 count then the elements. Reads are bounded:
// a count or length larger than the bytes left fails instead of allocating.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace depthbias::io {

class CdrReader {
 public:
  // Checks the encapsulation header; ok() is false (and why() says) when it is not
  // little-endian plain CDR.
  CdrReader(const std::uint8_t* data, std::size_t size);

  bool ok() const { return ok_; }
  const std::string& why() const { return why_; }

  std::uint8_t U8() { return Prim<std::uint8_t>(); }
  bool Bool() { return Prim<std::uint8_t>() != 0; }
  std::int32_t I32() { return Prim<std::int32_t>(); }
  std::uint32_t U32() { return Prim<std::uint32_t>(); }
  std::int64_t I64() { return Prim<std::int64_t>(); }
  double F64() { return Prim<double>(); }
  std::string String();
  // A sequence's element count, checked against the bytes left at elem_size each.
  std::uint32_t Count(std::size_t elem_size);
  // n raw bytes (a uint8[] payload); nullptr when fewer are left.
  const std::uint8_t* Bytes(std::size_t n);
  void Fail(const std::string& why) {
    if (ok_) why_ = why;
    ok_ = false;
  }

 private:
  template <typename T>
  T Prim() {
    const std::size_t align = sizeof(T);
    const std::size_t pad = (align - (pos_ - 4) % align) % align;
    if (!ok_ || size_ - pos_ < pad + sizeof(T)) {
      Fail("message ends early (at byte " + std::to_string(pos_) + ")");
      return T();
    }
    pos_ += pad;
    T v;
    std::memcpy(&v, data_ + pos_, sizeof(T));  // little-endian host (x86-64, arm64)
    pos_ += sizeof(T);
    return v;
  }

  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 4;
  bool ok_ = true;
  std::string why_;
};

}  // namespace depthbias::io
