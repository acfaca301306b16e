#include "io/bag_list.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <set>
#include <system_error>
#include <utility>

namespace depthbias::io {
namespace {

namespace fs = std::filesystem;

bool EndsWith(const std::string& name, const char* tail) {
  const std::size_t n = std::strlen(tail);
  return name.size() > n && name.compare(name.size() - n, n, tail) == 0;
}

// A recording file: a ROS 1 .bag, a rosbag2 .mcap or .db3.
bool EndsWithBag(const std::string& name) {
  return EndsWith(name, ".bag") || EndsWith(name, ".mcap") || EndsWith(name, ".db3");
}

// A rosbag2 recording folder: one recording, never searched into.
bool IsRosbag2Folder(const fs::path& dir) {
  std::error_code ec;
  return fs::is_regular_file(dir / "metadata.yaml", ec);
}

std::string KindOf(mode_t m) {
  if (S_ISFIFO(m)) return "a pipe (FIFO)";
  if (S_ISSOCK(m)) return "a socket";
  if (S_ISCHR(m) || S_ISBLK(m)) return "a device";
  if (S_ISDIR(m)) return "a folder";
  return "not a regular file";
}

class Walker {
 public:
  std::vector<ListedBag> found;

  // Lists one folder's entries (sorted), recursing into sub-folders. Returns false if the
  // folder itself cannot be listed (why in *why).
  bool Walk(const fs::path& dir, std::string* why) {
    struct stat st {};
    if (::stat(dir.c_str(), &st) != 0) {
      *why = std::strerror(errno);
      return false;
    }
    if (!visited_.insert({st.st_dev, st.st_ino}).second) return true;  // searched already
    std::error_code ec;
    fs::directory_iterator it(dir, ec);
    if (ec) {
      *why = "cannot list this folder: " + ec.message();
      return false;
    }
    std::vector<fs::path> entries;
    for (; it != fs::directory_iterator(); it.increment(ec)) {
      if (ec) {
        *why = "cannot list this folder: " + ec.message();
        return false;
      }
      entries.push_back(it->path());
    }
    std::sort(entries.begin(), entries.end());
    for (const fs::path& p : entries) Entry(p);
    return true;
  }

 private:
  void Entry(const fs::path& p) {
    const std::string path = p.string();
    const bool bag = EndsWithBag(p.filename().string());
    struct stat l {};
    if (::lstat(path.c_str(), &l) != 0) return;  // removed meanwhile
    struct stat st = l;
    if (S_ISLNK(l.st_mode) && ::stat(path.c_str(), &st) != 0) {
      const int err = errno;
      found.push_back({path, err == ELOOP ? "symbolic link in a loop (" + std::string(
                                                std::strerror(err)) + ")"
                                          : "symbolic link leads nowhere (" +
                                                std::string(std::strerror(err)) + ")"});
      return;
    }
    if (S_ISDIR(st.st_mode)) {
      if (IsRosbag2Folder(p)) {
        found.push_back({path, ""});
        return;
      }
      if (bag) {
        found.push_back({path, "is a folder named like a bag"});
        return;
      }
      std::string why;
      if (!Walk(p, &why)) found.push_back({path, why});
      return;
    }
    if (!bag) return;
    if (!S_ISREG(st.st_mode)) {
      found.push_back({path, "is " + KindOf(st.st_mode) + ", not a bag file"});
      return;
    }
    found.push_back({path, ""});
  }

  std::set<std::pair<dev_t, ino_t>> visited_;
};

}  // namespace

std::vector<ListedBag> ListBags(const std::vector<std::string>& inputs) {
  std::vector<ListedBag> out;
  for (const std::string& in : inputs) {
    std::error_code ec;
    if (!fs::is_directory(in, ec)) {
      out.push_back({in, ""});
      continue;
    }
    if (IsRosbag2Folder(in)) {  // named by the folder: "tp01/" (a shell's completion) is tp01
      std::string path = in;
      while (path.size() > 1 && path.back() == '/') path.pop_back();
      out.push_back({path, ""});
      continue;
    }
    Walker w;
    std::string why;
    if (!w.Walk(in, &why)) throw IoError(in + ": " + why);
    if (w.found.empty())
      throw IoError(in + ": no .bag file (nor .mcap, .db3 or rosbag2 folder) in this folder");
    std::sort(w.found.begin(), w.found.end(),
              [](const ListedBag& a, const ListedBag& b) { return a.path < b.path; });
    out.insert(out.end(), w.found.begin(), w.found.end());
  }
  return out;
}

}  // namespace depthbias::io
