#pragma once
// Decompression of MCAP chunks (https://mcap.dev/spec: compression "zstd" is a Zstandard frame,
// "lz4" an LZ4 frame) through Debian's libzstd and liblz4, and zstd compression for the writer.
// The output size is the one the chunk declares, already checked against the reader's limits by
// the caller; the decoders never write past it and a frame that does not fill it exactly is
// refused.

#include <cstddef>
#include <cstdint>
#include <string>

namespace depthbias::io {

// Decompresses src into dst (capacity exactly expected bytes). Returns "" on success, else what
// is wrong (unknown compression, damaged frame, size differs from expected).
std::string DecompressChunk(const std::string& compression, const std::uint8_t* src,
                            std::size_t src_size, std::uint8_t* dst, std::size_t expected);

// Zstandard frame of src at the given level (1 to 19). Throws std::runtime_error on failure.
std::string CompressZstd(const std::string& src, int level);

// CRC-32 (the one zlib computes) of bytes; MCAP's chunk and data CRCs.
std::uint32_t Crc32(const std::uint8_t* data, std::size_t size, std::uint32_t crc = 0);

}  // namespace depthbias::io
