#include "io/entry_store.h"

#include <filesystem>
#include <set>
#include <sstream>
#include <system_error>

#include "io/atomic_file.h"
#include "io/sha256.h"

namespace depthbias::io {
namespace fs = std::filesystem;

bool ReadEntry(const std::string& dir, const std::string& name, std::uint64_t max_bytes,
               std::string* bytes) {
  const std::string path = (fs::path(dir) / name).string();
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(path, ec);
  if (st.type() == fs::file_type::not_found) return false;
  *bytes = ReadFile(path, max_bytes);
  return true;
}

void WriteEntry(const std::string& dir, const std::string& name, const std::string& bytes) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw IoError(dir + ": cannot make the folder: " + ec.message());
  WriteFileAtomic((fs::path(dir) / name).string(), bytes);
}

std::string ProgramFilesDigest() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw IoError("/proc/self/exe: cannot read the link: " + ec.message());
  std::set<std::string> files{exe.string()};
  std::istringstream maps(ReadFile("/proc/self/maps", 16ull << 20));
  // address perms offset dev inode path
  for (std::string line; std::getline(maps, line);) {
    std::istringstream in(line);
    std::string address, perms, offset, dev, inode, path;
    in >> address >> perms >> offset >> dev >> inode;
    std::getline(in >> std::ws, path);
    if (perms.size() >= 3 && perms[2] == 'x' && !path.empty() && path[0] == '/')
      files.insert(path);
  }
  std::string out;
  for (const std::string& f : files) out += Sha256File(f) + " " + f + "\n";
  return out;
}

}  // namespace depthbias::io
