#pragma once
// Outputs are never left half-written: they go to a temporary file in the destination's own
// folder (same file system), are flushed, and then renamed over the destination in one step.
// An output that is not a regular file is never renamed over: a character device or a pipe
// (/dev/null, /dev/stdout, a FIFO with a reader) is written in place, a block device, a socket
// or a folder is refused. A symbolic link to a regular file keeps the link: its target is
// replaced; a link into /proc (/dev/stdout when the shell redirected it to a file) is written
// in place, so the shell's file gets the output.

#include <cstdint>
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
// written are they put in place (outputs written in place first, then the renames), so a
// failure while writing leaves every destination as it was. The renames of a set happen under
// an OutputSetLock: a set is committed as one against other runs. (A rename failing halfway, which
// takes a folder changed meanwhile, leaves the outputs renamed before it.) Signals wait for the
// renames (temp_files.h: CommitScope).
void WriteFilesAtomic(const std::vector<std::pair<std::string, std::string>>& files);

// An exclusive lock on the folders of a set of outputs (flock on each folder, taken in a fixed
// order, released on destruction). WriteFilesAtomic holds it while it puts a set in place, so
// two runs writing the same outputs at once leave one run's set, never the CSV of one and the
// JSON of the other; a reader that holds it sees a whole set. A folder that cannot be opened
// for reading is not locked (its outputs are still each whole).
class OutputSetLock {
 public:
  explicit OutputSetLock(const std::vector<std::string>& paths);
  ~OutputSetLock();
  OutputSetLock(const OutputSetLock&) = delete;
  OutputSetLock& operator=(const OutputSetLock&) = delete;

 private:
  std::vector<int> fds_;
};

// Throws IoError naming the output if an output is the same file as an input, or two outputs
// are the same path: a run never overwrites what it reads. Empty paths are ignored.
void CheckOutputs(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs);

// Before any work: throws IoError naming `path` if an output file could not be written there
// (its folder missing, not a folder or not writable — tried by creating and removing a
// temporary file —, the path a folder, a block device, a socket or a dangling link).
void CheckOutputFile(const std::string& path);
// The same for an output folder: the folder, or the nearest existing folder above it, must be
// writable; an existing non-folder is refused.
void CheckOutputFolder(const std::string& dir);
// Before a run that writes the files `names` into folder `dir`, about `bytes` in all: the folder
// is writable (or can be made), no file is an input or given twice, none exists as anything but
// a regular file, and the file system has room. Throws IoError naming what is wrong.
void CheckOutputSet(const std::string& dir, const std::vector<std::string>& names,
                    const std::vector<std::string>& inputs, double bytes);
// Bytes free for an unprivileged writer in the file system holding `dir` (or the nearest
// existing folder above it); -1 if unknown.
std::int64_t FreeBytes(const std::string& dir);

// Reads a whole file (or a pipe: /dev/stdin works). Throws IoError naming the file if it is
// missing, a folder, unreadable, or longer than max_bytes (so /dev/zero ends too).
constexpr std::uint64_t kMaxInputBytes = 256ull << 20;  // 256 MiB: tables and YAML are small
std::string ReadFile(const std::string& path, std::uint64_t max_bytes = kMaxInputBytes);

// True if `path` names an existing regular file.
bool FileExists(const std::string& path);

// True if both paths exist and name the same file (same device and inode): an output must
// never overwrite an input.
bool SameFile(const std::string& a, const std::string& b);

// The last path component ("a/b/c.bag" → "c.bag").
std::string BaseName(const std::string& path);

}  // namespace depthbias::io
