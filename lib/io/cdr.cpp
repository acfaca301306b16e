#include "io/cdr.h"

namespace depthbias::io {

CdrReader::CdrReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {
  static_assert(sizeof(double) == 8, "IEEE doubles");
  if (size < 4) {
    pos_ = size;
    Fail("shorter than its CDR header");
  } else if (data[0] != 0x00 || data[1] != 0x01) {
    Fail(data[0] == 0x00 && data[1] == 0x00
             ? "big-endian CDR (only little-endian, as ROS 2 writes on x86-64 and arm64)"
             : "not plain little-endian CDR (encapsulation " + std::to_string(data[0]) + " " +
                   std::to_string(data[1]) + ")");
  }
}

std::string CdrReader::String() {
  const std::uint32_t n = U32();
  if (!ok_) return "";
  if (n == 0) return "";  // some writers omit the NUL of an empty string
  if (n > size_ - pos_) {
    Fail("a string of " + std::to_string(n) + " bytes runs past the message's end");
    return "";
  }
  std::string s(reinterpret_cast<const char*>(data_ + pos_), n - 1);
  pos_ += n;
  return s;
}

std::uint32_t CdrReader::Count(std::size_t elem_size) {
  const std::uint32_t n = U32();
  if (ok_ && elem_size > 0 && n > (size_ - pos_) / elem_size) {
    Fail("a sequence of " + std::to_string(n) + " elements runs past the message's end");
    return 0;
  }
  return ok_ ? n : 0;
}

const std::uint8_t* CdrReader::Bytes(std::size_t n) {
  if (!ok_ || n > size_ - pos_) {
    Fail("a payload of " + std::to_string(n) + " bytes runs past the message's end");
    return nullptr;
  }
  const std::uint8_t* p = data_ + pos_;
  pos_ += n;
  return p;
}

}  // namespace depthbias::io
