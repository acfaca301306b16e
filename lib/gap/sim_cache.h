#pragma once
// A table's simulations as bytes, so that a later run on the same cells can take them instead of
// simulating again. The simulations (simulations.h) depend on the table's cells and metrics, the
// base parameters, the candidates' grids and the simulation options, never on the measured
// values: a campaign diagnosed again (a row fixed, another hold-out), another unit recorded with
// the same protocol, or an effect injected into the same table needs the same ones. They are
// about nine tenths of a diagnosis's time (the article's 128 rows: 14.6 of 17.5 s).
//
// The key is a text that names everything the simulations are made from: the caller's origin
// (what the base parameters were read from: the protocol's and sensor's bytes, and the build of
// the program), the seed, the sensor as written back (sim::FormatSensorYaml; the origin's
// sensor bytes hold the rest), the options but the threads (which change no
// result), every cell, the metrics and every candidate's grid. Encoded simulations carry their
// key and a checksum; decoding checks both and every size against the design and candidates,
// so a stale, truncated or altered entry is refused with a reason, never read. Values are
// stored as their bits: a run on decoded simulations writes the same outputs, byte for byte.
// Reading and writing the bytes is left to the caller (the library touches no file).

#include <functional>
#include <string>
#include <vector>

#include "gap/candidates.h"
#include "gap/design.h"
#include "gap/simulations.h"
#include "sim/stereo_sim.h"

namespace depthbias::gap {

// What makes a table's simulations: SimulateDesign, or a caller's stand-in for it that gives the
// same result (one that keeps them between runs).
using SimulateDesignFn =
    std::function<Simulations(const sim::SimParams& base, const Design& design,
                              const std::vector<Candidate>& candidates,
                              const SimulateOptions& options)>;

// The key of the simulations SimulateDesign(base, design, candidates, options) makes, given
// `origin`, a text naming what `base` was read from beyond its sensor and seed (its protocol) and
// the program that simulates. "" where they may not be kept: an empty origin, or a base that
// holds departures of its own.
std::string SimulationsKey(const std::string& origin, const sim::SimParams& base,
                           const Design& design, const std::vector<Candidate>& candidates,
                           const SimulateOptions& options);

// The simulations as bytes, with their key ("" on a machine that is not little-endian, whose
// bytes the format does not describe).
std::string EncodeSimulations(const Simulations& sims, const std::string& key);

// The simulations back from EncodeSimulations's bytes, made whole from the design, the base
// sensor and the candidates as SimulateDesign makes them. False, with a one-line reason, where
// the bytes are not an encoding of this key's simulations (another key, a different format, a
// checksum or a size that does not hold).
bool DecodeSimulations(const std::string& bytes, const std::string& key,
                       const sim::SimParams& base, const Design& design,
                       const std::vector<Candidate>& candidates, Simulations* out,
                       std::string* why);

}  // namespace depthbias::gap
