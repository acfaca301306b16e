#pragma once
// Outputs are never left half-written: they go to a temporary file in the destination's own
// folder (same file system), are flushed, and then renamed over the destination in one step.

#include <string>
#include <utility>
#include <vector>

#include "io/io_error.h"

namespace depthbias::io {

// Writes `contents` to `path` atomically (temp file in the same folder, then rename).
// Throws IoError naming the file if the folder is missing or not writable; on any failure
// the destination is left as it was and no temporary file remains.
void WriteFileAtomic(const std::string& path, const std::string& contents);

// Several outputs of one run: each is written to its temporary file, and only when all are
// written are they renamed into place, so a failure while writing leaves every destination as
// it was. (A rename failing halfway, which takes a folder made read-only meanwhile, leaves the
// outputs renamed before it.)
void WriteFilesAtomic(const std::vector<std::pair<std::string, std::string>>& files);

// Throws IoError naming the output if an output is the same file as an input, or two outputs
// are the same path: a run never overwrites what it reads. Empty paths are ignored.
void CheckOutputs(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs);

// Reads a whole file. Throws IoError naming the file if it is missing, a folder or unreadable.
std::string ReadFile(const std::string& path);

// True if `path` names an existing regular file.
bool FileExists(const std::string& path);

// True if both paths exist and name the same file (same device and inode): an output must
// never overwrite an input.
bool SameFile(const std::string& a, const std::string& b);

// The last path component ("a/b/c.bag" → "c.bag").
std::string BaseName(const std::string& path);

}  // namespace depthbias::io
