#include "pipeline/gap_cache.h"

#include <exception>
#include <stdexcept>
#include <utility>

#include "io/entry_store.h"
#include "io/sha256.h"

namespace depthbias::pipeline {

gap::SimulateDesignFn SimulationsKeptIn(const std::string& dir, const std::string& origin,
                                        std::function<void(const std::string&)> note) {
  return [dir, origin, note = std::move(note)](const sim::SimParams& base, const gap::Design& d,
                                               const std::vector<gap::Candidate>& candidates,
                                               const gap::SimulateOptions& options) {
    const std::string key = gap::SimulationsKey(origin, base, d, candidates, options);
    if (key.empty()) return gap::SimulateDesign(base, d, candidates, options);
    const std::string name = io::Sha256Hex(key).substr(0, 32) + ".sims";
    const std::string path = dir + "/" + name;
    try {
      std::string bytes, why;
      gap::Simulations kept;
      // 1024 rows of every candidate's grid are about 8 MB.
      if (io::ReadEntry(dir, name, 1ull << 30, &bytes)) {
        if (gap::DecodeSimulations(bytes, key, base, d, candidates, &kept, &why)) return kept;
        if (note) note(path + ": " + why + "; simulated again");
      }
    } catch (const std::exception& e) {
      if (note) note(std::string(e.what()) + "; simulated again");
    }
    gap::Simulations made = gap::SimulateDesign(base, d, candidates, options);
    try {
      const std::string bytes = gap::EncodeSimulations(made, key);
      if (bytes.empty()) throw std::runtime_error("this machine is not little-endian");
      io::WriteEntry(dir, name, bytes);
    } catch (const std::exception& e) {
      if (note) note(std::string("simulations not kept: ") + e.what());
    }
    return made;
  };
}

std::string SimulationsOrigin(const std::string& protocol_file, const std::string& sensor_file) {
  auto digest = [](const std::string& path) {
    return path.empty() ? std::string("none") : io::Sha256File(path);
  };
  return "protocol " + digest(protocol_file) + "; sensor " + digest(sensor_file) +
         "; program\n" + io::ProgramFilesDigest();
}

}  // namespace depthbias::pipeline
