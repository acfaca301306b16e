#include "io/atomic_file.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <set>
#include <vector>

#include "io/temp_files.h"
#include "records/number_text.h"

namespace depthbias::io {
namespace {

std::string Folder(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

std::string Error() { return std::strerror(errno); }

// Where an output goes: a file renamed into place at `path`, or written in place.
struct Target {
  std::string path;
  bool in_place = false;
};

std::string KindOf(mode_t m) {
  if (S_ISDIR(m)) return "a folder";
  if (S_ISBLK(m)) return "a block device";
  if (S_ISSOCK(m)) return "a socket";
  if (S_ISCHR(m)) return "a character device";
  if (S_ISFIFO(m)) return "a pipe";
  return "not a regular file";
}

Target Resolve(const std::string& path) {
  if (path.empty()) throw IoError("output path is empty");
  struct stat l {};
  if (::lstat(path.c_str(), &l) != 0) return {path, false};  // a new file
  struct stat st = l;
  const bool link = S_ISLNK(l.st_mode);
  if (link && ::stat(path.c_str(), &st) != 0)
    throw IoError(path + ": is a symbolic link that leads nowhere (" + Error() +
                  "); not writing through it");
  if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) return {path, true};
  if (!S_ISREG(st.st_mode))
    throw IoError(path + ": is " + KindOf(st.st_mode) + ", not a file to write");
  if (!link) return {path, false};
  // /dev/stdout redirected to a file by the shell leads through /proc: write the shell's file.
  if (path.rfind("/dev/", 0) == 0 || path.rfind("/proc/", 0) == 0) return {path, true};
  char buf[PATH_MAX];
  if (::realpath(path.c_str(), buf) == nullptr)
    throw IoError(path + ": cannot resolve the symbolic link: " + Error());
  return {buf, false};  // the link stays, its target is replaced
}

void WriteAll(int fd, const std::string& contents, const std::string& path,
              const std::string& cleanup) {
  size_t written = 0;
  while (written < contents.size()) {
    const ssize_t n = ::write(fd, contents.data() + written, contents.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string err = Error();
      ::close(fd);
      if (!cleanup.empty()) {
        ::unlink(cleanup.c_str());
        UnregisterTempFile(cleanup);
      }
      throw IoError(path + ": write failed: " + err);
    }
    written += static_cast<size_t>(n);
  }
}

// The descriptor a path names (/dev/stdout, /dev/stderr, /dev/fd/N, /proc/self/fd/N), or -1.
// Writing there goes through the process's own descriptor, so that its offset is shared with
// what the tool prints there too (a second open of a redirected file would write over it).
int OwnDescriptor(const std::string& path) {
  if (path == "/dev/stdout") return 1;
  if (path == "/dev/stderr") return 2;
  for (const char* prefix : {"/dev/fd/", "/proc/self/fd/"}) {
    const std::string p = prefix;
    if (path.rfind(p, 0) != 0 || path.size() == p.size()) continue;
    const std::string n = path.substr(p.size());
    if (n.size() > 6 || n.find_first_not_of("0123456789") != std::string::npos) return -1;
    return std::stoi(n);
  }
  return -1;
}

// Writes in place: a device or a pipe (never created, never renamed over).
void WriteInPlace(const std::string& path, const std::string& contents) {
  if (const int own = OwnDescriptor(path); own >= 0 && ::fcntl(own, F_GETFD) >= 0) {
    std::fflush(nullptr);  // what the tool printed before comes first
    const int fd = ::dup(own);
    if (fd < 0) throw IoError(path + ": cannot write: " + Error());
    WriteAll(fd, contents, path, "");
    ::close(fd);
    return;
  }
  struct stat st {};
  const bool regular = ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
  // O_NONBLOCK: a FIFO without a reader fails at once (ENXIO) instead of blocking for ever.
  const int fd = ::open(path.c_str(), O_WRONLY | O_NOCTTY | O_NONBLOCK | (regular ? O_TRUNC : 0));
  if (fd < 0) {
    if (errno == ENXIO) throw IoError(path + ": is a pipe that nobody reads");
    throw IoError(path + ": cannot open for writing: " + Error());
  }
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  WriteAll(fd, contents, path, "");
  if (::close(fd) != 0) throw IoError(path + ": write failed: " + Error());
}

// Writes contents to a new temporary file beside target and returns its name; on failure
// nothing is left and IoError names path.
std::string Stage(const std::string& path, const std::string& target,
                  const std::string& contents) {
  std::string tmpl = Folder(target) + "/." + BaseName(target) + ".tmp.XXXXXX";
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) {
    throw IoError(path + ": cannot create a file in folder '" + Folder(target) + "': " + Error());
  }
  const std::string tmp(name.data());
  RegisterTempFile(tmp);
  WriteAll(fd, contents, path, tmp);
  // mkstemp creates 0600; outputs get the usual 0644 (minus umask).
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, 0666 & ~mask);
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string err = Error();
    ::unlink(tmp.c_str());
    UnregisterTempFile(tmp);
    throw IoError(path + ": write failed: " + err);
  }
  return tmp;
}

void Drop(const std::string& tmp) {
  ::unlink(tmp.c_str());
  UnregisterTempFile(tmp);
}

void Commit(const std::string& tmp, const std::string& path, const std::string& target) {
  if (std::rename(tmp.c_str(), target.c_str()) != 0) {
    const std::string err = Error();
    Drop(tmp);
    throw IoError(path + ": cannot rename the finished file into place: " + err);
  }
  UnregisterTempFile(tmp);
}

// The same path, whether or not it exists yet.
bool SamePath(const std::string& a, const std::string& b) {
  if (SameFile(a, b)) return true;
  std::error_code ea, eb;
  const auto ca = std::filesystem::weakly_canonical(a, ea);
  const auto cb = std::filesystem::weakly_canonical(b, eb);
  return !ea && !eb && ca == cb;
}

// The folder itself if it exists, else the nearest existing folder above it.
std::string ExistingFolder(const std::string& dir) {
  std::filesystem::path p = dir.empty() ? "." : dir;
  std::error_code ec;
  while (!std::filesystem::exists(p, ec)) {
    if (!p.has_parent_path() || p.parent_path() == p) return ".";
    p = p.parent_path();
    if (p.empty()) return ".";
  }
  return p.string();
}

// Creates and removes a temporary file in folder: the one test of writability that holds for
// root, read-only mounts and full quotas alike.
void ProbeFolder(const std::string& folder, const std::string& output) {
  struct stat st {};
  if (::stat(folder.c_str(), &st) != 0)
    throw IoError(output + ": folder '" + folder + "' does not exist");
  if (!S_ISDIR(st.st_mode)) throw IoError(output + ": '" + folder + "' is not a folder");
  std::string tmpl = folder + "/.depthbias-probe.XXXXXX";
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) throw IoError(output + ": cannot write in folder '" + folder + "': " + Error());
  ::close(fd);
  ::unlink(name.data());
}

}  // namespace

std::string BaseName(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

bool SameFile(const std::string& a, const std::string& b) {
  struct stat sa {}, sb {};
  return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 &&
         sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

bool FileExists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

void WriteFileAtomic(const std::string& path, const std::string& contents) {
  WriteFilesAtomic({{path, contents}});
}

void WriteFilesAtomic(const std::vector<std::pair<std::string, std::string>>& files) {
  std::vector<Target> targets;
  for (const auto& f : files) targets.push_back(Resolve(f.first));
  std::vector<std::string> staged(files.size());
  try {
    for (size_t i = 0; i < files.size(); ++i)
      if (!targets[i].in_place) staged[i] = Stage(files[i].first, targets[i].path, files[i].second);
  } catch (...) {
    for (const std::string& tmp : staged)
      if (!tmp.empty()) Drop(tmp);
    throw;
  }
  std::vector<std::string> renamed;
  for (size_t k = 0; k < files.size(); ++k)
    if (!targets[k].in_place) renamed.push_back(targets[k].path);
  const OutputSetLock one_set(renamed);
  const CommitScope no_signal_now;
  size_t i = 0;
  try {
    // Outputs written in place first: they are the ones that can still fail (a pipe closed).
    for (; i < files.size(); ++i)
      if (targets[i].in_place) WriteInPlace(files[i].first, files[i].second);
    for (i = 0; i < files.size(); ++i) {
      if (targets[i].in_place) continue;
      Commit(staged[i], files[i].first, targets[i].path);
      staged[i].clear();
    }
  } catch (...) {
    for (const std::string& tmp : staged)
      if (!tmp.empty()) Drop(tmp);
    throw;
  }
}

OutputSetLock::OutputSetLock(const std::vector<std::string>& paths) {
  std::set<std::string> folders;  // a fixed order: two sets never wait on each other
  for (const std::string& p : paths) {
    std::error_code ec;
    const auto canon = std::filesystem::weakly_canonical(Folder(p), ec);
    folders.insert(ec ? Folder(p) : canon.string());
  }
  for (const std::string& f : folders) {
    const int fd = ::open(f.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) continue;
    while (::flock(fd, LOCK_EX) != 0 && errno == EINTR) {
    }
    fds_.push_back(fd);
  }
}

OutputSetLock::~OutputSetLock() {
  for (auto it = fds_.rbegin(); it != fds_.rend(); ++it) {
    ::flock(*it, LOCK_UN);
    ::close(*it);
  }
}

void CheckOutputs(const std::vector<std::string>& outputs,
                  const std::vector<std::string>& inputs) {
  for (size_t i = 0; i < outputs.size(); ++i) {
    if (outputs[i].empty()) continue;
    for (const std::string& in : inputs)
      if (!in.empty() && FileExists(outputs[i]) && SameFile(outputs[i], in))
        throw IoError(outputs[i] + ": is also an input (" + in +
                      "); an output never overwrites an input");
    for (size_t k = i + 1; k < outputs.size(); ++k)
      if (!outputs[k].empty() && SamePath(outputs[i], outputs[k]))
        throw IoError(outputs[i] + ": given for two outputs");
  }
}

void CheckOutputFile(const std::string& path) {
  const Target t = Resolve(path);
  if (t.in_place) return;  // a device or a pipe: opened when written
  struct stat st {};
  if (::stat(t.path.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
    throw IoError(path + ": is a folder, not a file to write");
  ProbeFolder(Folder(t.path), path);
}

void CheckOutputFolder(const std::string& dir) {
  struct stat st {};
  if (::stat(dir.c_str(), &st) == 0) {
    if (!S_ISDIR(st.st_mode)) throw IoError(dir + ": exists and is not a folder");
    ProbeFolder(dir, dir);
    return;
  }
  ProbeFolder(ExistingFolder(dir), dir);
}

void CheckOutputSet(const std::string& dir, const std::vector<std::string>& names,
                    const std::vector<std::string>& inputs, double bytes) {
  CheckOutputFolder(dir);
  std::vector<std::string> outputs;
  for (const std::string& n : names) outputs.push_back((std::filesystem::path(dir) / n).string());
  CheckOutputs(outputs, inputs);
  for (const std::string& out : outputs) {
    struct stat st {};
    if (::stat(out.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
      throw IoError(out + ": exists and is not a regular file; an output is never written over it");
  }
  const std::int64_t free_bytes = FreeBytes(dir);
  if (free_bytes >= 0 && bytes > static_cast<double>(free_bytes))
    throw IoError(dir + ": the outputs need about " +
                  records::BytesText(bytes) + ", " +
                  records::BytesText(static_cast<double>(free_bytes)) + " are free there");
}

std::int64_t FreeBytes(const std::string& dir) {
  struct statvfs s {};
  if (::statvfs(ExistingFolder(dir).c_str(), &s) != 0) return -1;
  return static_cast<std::int64_t>(s.f_bavail) * static_cast<std::int64_t>(s.f_frsize);
}

std::string ReadFile(const std::string& path, std::uint64_t max_bytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) throw IoError(path + ": no such file");
    throw IoError(path + ": cannot read: " + Error());
  }
  if (S_ISDIR(st.st_mode)) throw IoError(path + ": is a folder, not a file");
  if (S_ISREG(st.st_mode) && static_cast<std::uint64_t>(st.st_size) > max_bytes)
    throw IoError(path + ": is " + records::BytesText(static_cast<double>(st.st_size)) +
                  ", more than the " + records::BytesText(static_cast<double>(max_bytes)) +
                  " an input of this kind may be");
  // O_NONBLOCK: a FIFO nobody writes opens at once (and then reads as empty) instead of
  // blocking the run for ever.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOCTTY | O_NONBLOCK);
  if (fd < 0) throw IoError(path + ": cannot open for reading: " + Error());
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  std::string out;
  char buf[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string err = Error();
      ::close(fd);
      throw IoError(path + ": read failed: " + err);
    }
    if (out.size() + static_cast<size_t>(n) > max_bytes) {
      ::close(fd);
      throw IoError(path + ": longer than the " +
                    records::BytesText(static_cast<double>(max_bytes)) +
                    " an input of this kind may be");
    }
    out.append(buf, static_cast<size_t>(n));
  }
  ::close(fd);
  return out;
}

}  // namespace depthbias::io
