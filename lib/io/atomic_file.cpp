#include "io/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

namespace depthbias::io {
namespace {

std::string Folder(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
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

namespace {

// Writes contents to a new temporary file beside path and returns its name; on failure nothing
// is left and IoError names path.
std::string Stage(const std::string& path, const std::string& contents) {
  if (path.empty()) throw IoError("output path is empty");
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
    throw IoError(path + ": is a folder, cannot write a file there");
  }
  std::string tmpl = Folder(path) + "/." + BaseName(path) + ".tmp.XXXXXX";
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) {
    throw IoError(path + ": cannot create a file in folder '" + Folder(path) +
                  "': " + std::strerror(errno));
  }
  const std::string tmp(name.data());
  size_t written = 0;
  while (written < contents.size()) {
    const ssize_t n = ::write(fd, contents.data() + written, contents.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string err = std::strerror(errno);
      ::close(fd);
      ::unlink(tmp.c_str());
      throw IoError(path + ": write failed: " + err);
    }
    written += static_cast<size_t>(n);
  }
  // mkstemp creates 0600; outputs get the usual 0644 (minus umask).
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, 0666 & ~mask);
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string err = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw IoError(path + ": write failed: " + err);
  }
  return tmp;
}

void Commit(const std::string& tmp, const std::string& path) {
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string err = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw IoError(path + ": cannot rename the finished file into place: " + err);
  }
}

// The same path, whether or not it exists yet.
bool SamePath(const std::string& a, const std::string& b) {
  if (SameFile(a, b)) return true;
  std::error_code ea, eb;
  const auto ca = std::filesystem::weakly_canonical(a, ea);
  const auto cb = std::filesystem::weakly_canonical(b, eb);
  return !ea && !eb && ca == cb;
}

}  // namespace

void WriteFileAtomic(const std::string& path, const std::string& contents) {
  Commit(Stage(path, contents), path);
}

void WriteFilesAtomic(const std::vector<std::pair<std::string, std::string>>& files) {
  std::vector<std::string> staged;
  try {
    for (const auto& [path, contents] : files) staged.push_back(Stage(path, contents));
  } catch (...) {
    for (const std::string& tmp : staged) ::unlink(tmp.c_str());
    throw;
  }
  for (size_t i = 0; i < staged.size(); ++i) {
    try {
      Commit(staged[i], files[i].first);
    } catch (...) {
      for (size_t k = i + 1; k < staged.size(); ++k) ::unlink(staged[k].c_str());
      throw;
    }
  }
}

void CheckOutputs(const std::vector<std::string>& outputs,
                  const std::vector<std::string>& inputs) {
  for (size_t i = 0; i < outputs.size(); ++i) {
    if (outputs[i].empty()) continue;
    for (const std::string& in : inputs)
      if (!in.empty() && SameFile(outputs[i], in))
        throw IoError(outputs[i] + ": is also an input (" + in +
                      "); an output never overwrites an input");
    for (size_t k = i + 1; k < outputs.size(); ++k)
      if (!outputs[k].empty() && SamePath(outputs[i], outputs[k]))
        throw IoError(outputs[i] + ": given for two outputs");
  }
}

std::string ReadFile(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw IoError(path + ": no such file");
  if (S_ISDIR(st.st_mode)) throw IoError(path + ": is a folder, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open for reading");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw IoError(path + ": read failed");
  return ss.str();
}

}  // namespace depthbias::io
