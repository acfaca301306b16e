#include "io/chunk_compression.h"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <stdexcept>

namespace depthbias::io {
namespace {

std::string Zstd(const std::uint8_t* src, std::size_t n, std::uint8_t* dst, std::size_t expected) {
  const unsigned long long declared = ZSTD_getFrameContentSize(src, n);
  if (declared == ZSTD_CONTENTSIZE_ERROR) return "not a zstd frame";
  if (declared != ZSTD_CONTENTSIZE_UNKNOWN && declared != expected)
    return "zstd frame holds " + std::to_string(declared) + " bytes, the chunk says " +
           std::to_string(expected);
  // One context per thread, kept: a fresh one per chunk is allocated and initialised each time.
  struct Context {
    ZSTD_DCtx* dctx = ZSTD_createDCtx();
    ~Context() { ZSTD_freeDCtx(dctx); }
  };
  thread_local Context context;
  if (!context.dctx) return "zstd: cannot make a decompression context";
  const std::size_t got = ZSTD_decompressDCtx(context.dctx, dst, expected, src, n);
  if (ZSTD_isError(got)) return std::string("zstd: ") + ZSTD_getErrorName(got);
  if (got != expected)
    return "zstd frame holds " + std::to_string(got) + " bytes, the chunk says " +
           std::to_string(expected);
  return "";
}

std::string Lz4(const std::uint8_t* src, std::size_t n, std::uint8_t* dst, std::size_t expected) {
  LZ4F_dctx* ctx = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)))
    return "lz4: cannot make a decompression context";
  std::string why;
  std::size_t in_pos = 0, out_pos = 0;
  while (true) {
    std::size_t in_size = n - in_pos, out_size = expected - out_pos;
    const std::size_t hint =
        LZ4F_decompress(ctx, dst + out_pos, &out_size, src + in_pos, &in_size, nullptr);
    if (LZ4F_isError(hint)) {
      why = std::string("lz4: ") + LZ4F_getErrorName(hint);
      break;
    }
    in_pos += in_size;
    out_pos += out_size;
    if (hint == 0) break;  // frame complete
    if (in_size == 0 && out_size == 0) {
      why = in_pos >= n ? "lz4 frame ends early" : "lz4 frame holds more than the chunk says";
      break;
    }
  }
  LZ4F_freeDecompressionContext(ctx);
  if (why.empty() && out_pos != expected)
    why = "lz4 frame holds " + std::to_string(out_pos) + " bytes, the chunk says " +
          std::to_string(expected);
  return why;
}

}  // namespace

std::string DecompressChunk(const std::string& compression, const std::uint8_t* src,
                            std::size_t src_size, std::uint8_t* dst, std::size_t expected) {
  if (compression == "zstd") return Zstd(src, src_size, dst, expected);
  if (compression == "lz4") return Lz4(src, src_size, dst, expected);
  if (compression.empty()) return "an uncompressed chunk is not decompressed";
  return "unknown chunk compression '" + compression.substr(0, 32) + "'";
}

std::string CompressZstd(const std::string& src, int level) {
  std::string out(ZSTD_compressBound(src.size()), '\0');
  const std::size_t n = ZSTD_compress(&out[0], out.size(), src.data(), src.size(), level);
  if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
  out.resize(n);
  return out;
}

std::uint32_t Crc32(const std::uint8_t* data, std::size_t size, std::uint32_t crc) {
  while (size > 0) {
    const uInt step = static_cast<uInt>(std::min<std::size_t>(size, 1u << 30));
    crc = static_cast<std::uint32_t>(::crc32(crc, data, step));
    data += step;
    size -= step;
  }
  return crc;
}

}  // namespace depthbias::io
