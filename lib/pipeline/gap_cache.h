#pragma once
// A table's simulations kept in a folder between runs of the gap diagnosis (gap/sim_cache.h):
// `diagnose_gap --cache DIR`. Each entry is one file, DIR/<digest of its key>.sims, written
// whole or not at all (io/atomic_file.h). An entry that cannot be read (another format, a
// checksum or a size that does not hold, made for other cells or another build) is noted and
// simulated again, then written over; an entry that cannot be written is noted and the run goes
// on. Runs on kept simulations write the same outputs, byte for byte.

#include <functional>
#include <string>

#include "gap/sim_cache.h"

namespace depthbias::pipeline {

// A stand-in for gap::SimulateDesign that keeps its results in `dir` under the key
// gap::SimulationsKey(origin, ...). `note` gets one line for each entry it could not read or
// write. An empty origin keeps nothing.
gap::SimulateDesignFn SimulationsKeptIn(const std::string& dir, const std::string& origin,
                                        std::function<void(const std::string&)> note);

// The origin of a diagnosis's simulations: the bytes of the protocol and sensor files its base
// parameters were read from ("" for a file not given) and this program's build (the SHA-256 of
// its executable and of every shared library mapped into it: io::ProgramFilesDigest). Throws
// io::IoError when one cannot be read.
std::string SimulationsOrigin(const std::string& protocol_file, const std::string& sensor_file);

}  // namespace depthbias::pipeline
