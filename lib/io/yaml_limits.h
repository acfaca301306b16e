#pragma once
// Limits every YAML (and JSON) input of the tools is held to, checked before any reader walks
// the document: an 818-byte alias bomb (nine anchors, each a map of nine aliases of the one
// before) expands to 9^9 nodes when walked, and ran for minutes into std::bad_alloc. Files
// are at most kMaxYamlBytes, nested at most kMaxYamlDepth deep, and at most kMaxYamlNodes
// nodes when every alias is expanded; anything beyond is refused with one line naming the file.

#include <cstddef>
#include <string>

#include <yaml-cpp/yaml.h>

#include "io/io_error.h"

namespace depthbias::io {

constexpr std::size_t kMaxYamlBytes = 1u << 20;  // 1 MiB: the largest config is a few kB
constexpr int kMaxYamlDepth = 32;                // nesting of maps and lists
constexpr std::size_t kMaxYamlNodes = 100000;    // with aliases expanded

// Parses text with yaml-cpp and checks the limits; throws IoError naming the file (and line)
// for invalid YAML or a document beyond a limit.
YAML::Node LoadYaml(const std::string& text, const std::string& file);

// The same checks for parsers outside io that take text (the simulator's protocol, sensor and
// effects files): throws IoError, or returns and the text is safe to walk.
void CheckYamlText(const std::string& text, const std::string& file);

// ReadFile (at most kMaxYamlBytes) and CheckYamlText: the text of a YAML input.
std::string ReadYamlFile(const std::string& path);

}  // namespace depthbias::io
