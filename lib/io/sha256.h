#pragma once
// SHA-256 (FIPS 180-4), for the provenance of outputs: which input file exactly they came from.

#include <string>

namespace depthbias::io {

// Hex digest (64 lower-case characters) of a byte string.
std::string Sha256Hex(const std::string& bytes);
// Hex digest of a file's contents; throws IoError naming the file if it cannot be read.
std::string Sha256File(const std::string& path);

}  // namespace depthbias::io
