#pragma once
// The recordings a command line names: files as given, folders searched (recursively, through
// symbolic links to folders, each folder once) for recordings in name order: *.bag, *.mcap and
// *.db3 files, and rosbag2 folders (a folder holding metadata.yaml is one recording). Nothing is
// skipped silently: what the search meets and cannot read comes back with the reason, so a
// batch reports it in its own row (status error) instead of leaving it out.

#include <string>
#include <vector>

#include "io/io_error.h"

namespace depthbias::io {

struct ListedBag {
  std::string path;
  std::string problem;  // empty for a recording to read; else why it cannot be read
};

// Paths of the recordings named by inputs, in order. A path that is not a folder is kept as it
// is (reading it reports what is wrong with it). In a folder: a *.bag regular file is listed; a
// *.bag that is a pipe, device, socket or folder, any symbolic link that leads nowhere or into
// a loop, and any sub-folder that cannot be listed are listed with their problem; a symbolic
// link back to a folder already searched is not searched again. Throws IoError naming a folder
// given on the command line that cannot be listed or holds nothing to list.
std::vector<ListedBag> ListBags(const std::vector<std::string>& inputs);

}  // namespace depthbias::io
