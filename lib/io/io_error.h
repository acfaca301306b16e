#pragma once
// The one exception io throws for tables, manifests, YAML and plain files (bags have BagError).
// what() is one line naming the file (and line and column where there is one) and what is wrong.

#include <stdexcept>
#include <string>

namespace depthbias::io {

class IoError : public std::runtime_error {
 public:
  explicit IoError(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace depthbias::io
