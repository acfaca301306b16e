#pragma once
// The recordings a command line names: files as given, folders searched (recursively) for
// *.bag files in name order.

#include <string>
#include <vector>

#include "io/io_error.h"

namespace depthbias::io {

// Paths of the recordings named by inputs, in order. A path that is not a folder is kept as it
// is (reading it reports what is wrong with it). Throws IoError naming a folder that holds no
// .bag file.
std::vector<std::string> ListBags(const std::vector<std::string>& inputs);

}  // namespace depthbias::io
