// rosbag loads its encryptor plugin through pluginlib, which asks rospack, which keeps a cache
// in $ROS_HOME or ~/.ros and prints "[rospack] Warning: cannot create rospack cache directory"
// on stderr when it cannot write there (HOME read-only or missing, a service account). When
// that is so and ROS_HOME is not set, ROS_HOME is pointed at a private folder of this user in
// the temporary folder, so that reading a bag prints nothing.
#include <pwd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <mutex>
#include <string>
#include <vector>

#include "io/bag.h"

namespace depthbias::io {
namespace {

// True if folder `dir`/.ros exists and is writable, or could be made in a writable `dir`.
bool RosCacheWritable(const std::string& home) {
  if (home.empty()) return false;
  const std::string ros = home + "/.ros";
  struct stat st {};
  if (::stat(ros.c_str(), &st) == 0) return S_ISDIR(st.st_mode) && ::access(ros.c_str(), W_OK) == 0;
  return ::stat(home.c_str(), &st) == 0 && S_ISDIR(st.st_mode) &&
         ::access(home.c_str(), W_OK) == 0;
}

// A folder only this user can write, or "" if none can be had.
std::string PrivateFolder() {
  const char* tmp = std::getenv("TMPDIR");
  const std::string base = tmp && *tmp ? tmp : "/tmp";
  const std::string dir = base + "/depthbias-ros-" + std::to_string(::getuid());
  if (::mkdir(dir.c_str(), 0700) == 0) return dir;
  struct stat st {};
  // An existing one is used only if it is a real folder of ours that nobody else can write.
  if (errno == EEXIST && ::lstat(dir.c_str(), &st) == 0 && S_ISDIR(st.st_mode) &&
      st.st_uid == ::getuid() && (st.st_mode & 022) == 0)
    return dir;
  std::string tmpl = base + "/depthbias-ros.XXXXXX";
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  return ::mkdtemp(name.data()) ? std::string(name.data()) : "";
}

}  // namespace

void PrepareRosEnvironment() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (const char* r = std::getenv("ROS_HOME"); r && *r) return;
    const char* home = std::getenv("HOME");
    const passwd* pw = ::getpwuid(::getuid());
    const bool ok = (home && *home ? RosCacheWritable(home) : true) &&
                    (pw && pw->pw_dir ? RosCacheWritable(pw->pw_dir) : true) &&
                    ((home && *home) || (pw && pw->pw_dir));
    if (ok) return;
    const std::string dir = PrivateFolder();
    if (!dir.empty()) ::setenv("ROS_HOME", dir.c_str(), 0);
  });
}

}  // namespace depthbias::io
