#pragma once
// Stage configuration files and small JSON side inputs, read with yaml-cpp (JSON is read as
// YAML). Values come back as text so each stage's parameters struct parses and checks its own
// keys: YAML overrides only what it names.

#include <array>
#include <map>
#include <string>
#include <vector>

#include "io/io_error.h"

namespace depthbias::io {

struct ConfigEntry {
  std::string key;    // nested maps joined with '.', e.g. "ground.distance_m"
  std::string value;  // the scalar's text
  int line = 0;       // 1-based line in the file
};

// Every scalar of a YAML mapping, in file order. An empty file gives no entries. Throws IoError
// naming the file (and line) for a missing file, a YAML syntax error, a top level that is not a
// mapping, or a sequence value.
std::vector<ConfigEntry> ReadConfigScalars(const std::string& path);
std::vector<ConfigEntry> ParseConfigScalars(const std::string& text, const std::string& file);

// Boxes of the manual method, as JSON {"name.bag": [u0, v0, u1, v1], ...} in pixels
// ([u0, u1) × [v0, v1)). Throws IoError naming the file and the bag for anything else.
std::map<std::string, std::array<double, 4>> ReadBoxes(const std::string& path);
std::map<std::string, std::array<double, 4>> ParseBoxes(const std::string& text,
                                                         const std::string& file);

}  // namespace depthbias::io
