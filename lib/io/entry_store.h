#pragma once
// A folder of entries kept between runs (diagnose_gap --cache): each entry one whole file, put
// in place atomically (atomic_file.h), so a reader sees an entry whole or not at all; and the
// files this program is made of, so that what it kept is not taken back by another build.

#include <cstdint>
#include <string>

#include "io/io_error.h"

namespace depthbias::io {

// DIR/NAME's bytes into *bytes; false where there is no such entry (or no such folder). Throws
// IoError naming the file when it is there but cannot be read (a folder, too long, unreadable).
bool ReadEntry(const std::string& dir, const std::string& name, std::uint64_t max_bytes,
               std::string* bytes);

// DIR/NAME written whole, DIR made first where it is missing. Throws IoError naming what failed.
void WriteEntry(const std::string& dir, const std::string& name, const std::string& bytes);

// This program as files, one line each, "<sha256> <path>", in path order: its executable and
// every file mapped executable into it (/proc/self/maps: its shared libraries, whose code the
// results depend on too). Throws IoError where one cannot be read.
std::string ProgramFilesDigest();

}  // namespace depthbias::io
