#pragma once
// Private to io. rosbag::Bag loads its encryptor plugin with class_loader, which is not
// thread-safe: two bags made or opened at once on two threads fail with "Could not create object
// of class type rosbag::NoEncryptor". Every rosbag::Bag of the process is made, opened, closed and
// destroyed through GuardedBag, under one lock; reading and writing messages need no lock.

#include <rosbag/bag.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

namespace depthbias::io::bag_detail {

inline std::mutex& RosbagLock() {
  static std::mutex mutex;
  return mutex;
}

class GuardedBag {
 public:
  GuardedBag() {
    std::lock_guard<std::mutex> lock(RosbagLock());
    bag_ = std::make_unique<rosbag::Bag>();
  }
  ~GuardedBag() {
    std::lock_guard<std::mutex> lock(RosbagLock());
    bag_.reset();
  }
  GuardedBag(const GuardedBag&) = delete;
  GuardedBag& operator=(const GuardedBag&) = delete;

  void Open(const std::string& path, std::uint32_t mode) {
    std::lock_guard<std::mutex> lock(RosbagLock());
    bag_->open(path, mode);
  }
  void Close() {
    std::lock_guard<std::mutex> lock(RosbagLock());
    bag_->close();
  }
  rosbag::Bag& operator*() { return *bag_; }
  rosbag::Bag* operator->() { return bag_.get(); }

 private:
  std::unique_ptr<rosbag::Bag> bag_;
};

}  // namespace depthbias::io::bag_detail
