#include "pipeline/gap_cache.h"

#include <exception>
#include <filesystem>
#include <system_error>
#include <utility>

#include "io/atomic_file.h"
#include "io/sha256.h"

namespace depthbias::pipeline {
namespace fs = std::filesystem;

gap::SimulateDesignFn SimulationsKeptIn(const std::string& dir, const std::string& origin,
                                        std::function<void(const std::string&)> note) {
  return [dir, origin, note = std::move(note)](const sim::SimParams& base, const gap::Design& d,
                                               const std::vector<gap::Candidate>& candidates,
                                               const gap::SimulateOptions& options) {
    const std::string key = gap::SimulationsKey(origin, base, d, candidates, options);
    if (key.empty()) return gap::SimulateDesign(base, d, candidates, options);
    const std::string path =
        (fs::path(dir) / (io::Sha256Hex(key).substr(0, 32) + ".sims")).string();
    std::error_code ec;
    if (fs::exists(path, ec)) {
      std::string why;
      try {
        gap::Simulations kept;
        // 1024 rows of every candidate's grid are about 8 MB.
        if (gap::DecodeSimulations(io::ReadFile(path, 1ull << 30), key, base, d, candidates,
                                   &kept, &why))
          return kept;
        why = path + ": " + why;
      } catch (const std::exception& e) {
        why = e.what();
      }
      if (note) note(why + "; simulated again");
    }
    gap::Simulations made = gap::SimulateDesign(base, d, candidates, options);
    try {
      fs::create_directories(dir);
      io::WriteFileAtomic(path, gap::EncodeSimulations(made, key));
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
  return "program " + io::Sha256File("/proc/self/exe") + "; protocol " + digest(protocol_file) +
         "; sensor " + digest(sensor_file);
}

}  // namespace depthbias::pipeline
