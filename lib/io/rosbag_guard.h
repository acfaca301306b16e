#pragma once
// Private to io. rosbag::Bag loads its encryptor plugin with class_loader, which is not
// thread-safe: two bags made or opened at once on two threads fail with "Could not create object
// of class type rosbag::NoEncryptor". Every rosbag::Bag of the process is made, opened, closed and
// destroyed through GuardedBag, under one lock; reading and writing messages need no lock.
//
// rosbag::Bag's destructor calls close() again, and close() throws when it cannot write the
// bag's index (a full disk): an exception out of a destructor is std::terminate (simulate died
// with "terminate called after throwing rosbag::BagIOException"). GuardedBag therefore never
// lets rosbag close a bag twice on a failing file: when close() throws, the bag's file
// descriptor is pointed at /dev/null, rosbag's second close() succeeds there, and the first
// error is rethrown. The caller removes the file.

#include <dirent.h>
#include <fcntl.h>
#include <rosbag/bag.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "io/bag.h"

namespace depthbias::io::bag_detail {

inline std::mutex& RosbagLock() {
  static std::mutex mutex;
  return mutex;
}

// The descriptor this process holds open on the file at `path` (same device and inode), or -1.
inline int FindDescriptor(const std::string& path) {
  struct stat want {};
  if (::stat(path.c_str(), &want) != 0) return -1;
  DIR* d = ::opendir("/proc/self/fd");
  if (!d) return -1;
  int found = -1;
  const int own = ::dirfd(d);
  while (const dirent* e = ::readdir(d)) {
    char* end = nullptr;
    const long fd = std::strtol(e->d_name, &end, 10);
    if (end == e->d_name || *end != '\0' || fd == own) continue;
    struct stat st {};
    if (::fstat(static_cast<int>(fd), &st) == 0 && st.st_dev == want.st_dev &&
        st.st_ino == want.st_ino) {
      found = static_cast<int>(fd);
      break;
    }
  }
  ::closedir(d);
  return found;
}

class GuardedBag {
 public:
  GuardedBag() {
    PrepareRosEnvironment();
    std::lock_guard<std::mutex> lock(RosbagLock());
    bag_ = std::make_unique<rosbag::Bag>();
  }
  ~GuardedBag() {
    std::lock_guard<std::mutex> lock(RosbagLock());
    CloseLocked(false);
    bag_.reset();  // closed: its destructor has nothing left to throw
  }
  GuardedBag(const GuardedBag&) = delete;
  GuardedBag& operator=(const GuardedBag&) = delete;

  void Open(const std::string& path, std::uint32_t mode) {
    std::lock_guard<std::mutex> lock(RosbagLock());
    bag_->open(path, mode);
    if (mode & (rosbag::bagmode::Write | rosbag::bagmode::Append)) {
      fd_ = FindDescriptor(path);
      struct stat st {};
      if (fd_ >= 0 && ::fstat(fd_, &st) == 0) file_id_ = {st.st_dev, st.st_ino};
    }
  }
  // Throws what rosbag threw; the bag is closed either way.
  void Close() {
    std::lock_guard<std::mutex> lock(RosbagLock());
    CloseLocked(true);
  }
  rosbag::Bag& operator*() { return *bag_; }
  rosbag::Bag* operator->() { return bag_.get(); }

 private:
  void CloseLocked(bool rethrow) {
    if (!bag_ || !bag_->isOpen()) return;
    try {
      bag_->close();
      fd_ = -1;
      return;
    } catch (...) {
      Abandon();
      if (rethrow) throw;
    }
  }
  // After a failed close: the rest of rosbag's writes go to /dev/null so that its close ends.
  // Only while the descriptor is still the bag's own (rosbag closes it only once its writes
  // succeeded; were it closed and reused, it must not be touched).
  void Abandon() {
    const int fd = fd_;
    fd_ = -1;
    struct stat st {};
    const bool own = fd >= 0 && ::fstat(fd, &st) == 0 && st.st_dev == file_id_.first &&
                     st.st_ino == file_id_.second;
    if (own) {
      const int null_fd = ::open("/dev/null", O_WRONLY);
      if (null_fd >= 0) {
        ::dup2(null_fd, fd);
        ::close(null_fd);
        try {
          bag_->close();
          return;
        } catch (...) {
        }
      }
    }
    // Still failing, or its descriptor unknown: the object is given up unfreed rather than
    // destroyed, since its destructor would close (and throw) again. Its file is removed by the
    // caller; the descriptor stays open until the process ends.
    (void)bag_.release();
  }

  std::unique_ptr<rosbag::Bag> bag_;
  int fd_ = -1;  // the written bag's descriptor, for Abandon
  std::pair<dev_t, ino_t> file_id_{0, 0};
};

}  // namespace depthbias::io::bag_detail
