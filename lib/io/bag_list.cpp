#include "io/bag_list.h"

#include <algorithm>
#include <filesystem>
#include <system_error>

namespace depthbias::io {

std::vector<std::string> ListBags(const std::vector<std::string>& inputs) {
  namespace fs = std::filesystem;
  std::vector<std::string> out;
  for (const std::string& in : inputs) {
    std::error_code ec;
    if (!fs::is_directory(in, ec)) {
      out.push_back(in);
      continue;
    }
    std::vector<std::string> found;
    fs::recursive_directory_iterator it(in, fs::directory_options::skip_permission_denied, ec);
    if (ec) throw IoError(in + ": cannot list this folder: " + ec.message());
    for (; it != fs::recursive_directory_iterator(); it.increment(ec)) {
      if (ec) throw IoError(in + ": cannot list this folder: " + ec.message());
      if (it->path().extension() == ".bag" && it->is_regular_file(ec)) found.push_back(it->path());
    }
    if (found.empty()) throw IoError(in + ": no .bag file in this folder");
    std::sort(found.begin(), found.end());
    out.insert(out.end(), found.begin(), found.end());
  }
  return out;
}

}  // namespace depthbias::io
