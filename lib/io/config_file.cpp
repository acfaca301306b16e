#include "io/config_file.h"

#include <cmath>
#include <cstdlib>

#include <yaml-cpp/yaml.h>

#include "io/atomic_file.h"
#include "io/yaml_limits.h"

namespace depthbias::io {
namespace {

YAML::Node Load(const std::string& text, const std::string& file) { return LoadYaml(text, file); }

// A mapping's key as text; a key that is a list or a map is refused.
std::string Key(const YAML::Node& key, const std::string& file) {
  if (!key.IsScalar())
    throw IoError(file + ":" + std::to_string(key.Mark().line + 1) +
                  ": a key must be a plain name, not a list or a map");
  return key.Scalar();
}

void Flatten(const YAML::Node& node, const std::string& prefix, const std::string& file,
             std::vector<ConfigEntry>* out) {
  for (const auto& kv : node) {
    const std::string key = prefix + Key(kv.first, file);
    const YAML::Node& v = kv.second;
    const int line = v.Mark().line + 1;
    if (v.IsMap()) {
      Flatten(v, key + ".", file, out);
    } else if (v.IsScalar()) {
      out->push_back({key, v.Scalar(), line});
    } else if (v.IsNull()) {
      throw IoError(file + ":" + std::to_string(line) + ": '" + key + "' has no value");
    } else {
      throw IoError(file + ":" + std::to_string(line) + ": '" + key +
                    "' must be a single value, not a list");
    }
  }
}

}  // namespace

std::vector<ConfigEntry> ParseConfigScalars(const std::string& text, const std::string& file) {
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    throw IoError(file + ": is empty (expected key: value lines)");
  const YAML::Node root = Load(text, file);
  std::vector<ConfigEntry> out;
  if (root.IsNull()) return out;  // comments only: no overrides
  if (!root.IsMap()) throw IoError(file + ": expected a mapping of key: value at the top level");
  Flatten(root, "", file, &out);
  return out;
}

std::vector<ConfigEntry> ReadConfigScalars(const std::string& path) {
  return ParseConfigScalars(ReadFile(path, kMaxYamlBytes), path);
}

std::map<std::string, std::array<double, 4>> ParseBoxes(const std::string& text,
                                                         const std::string& file) {
  const YAML::Node root = Load(text, file);
  if (!root.IsMap()) throw IoError(file + ": expected {\"bag name\": [u0, v0, u1, v1], ...}");
  std::map<std::string, std::array<double, 4>> boxes;
  for (const auto& kv : root) {
    const std::string name = Key(kv.first, file);
    const YAML::Node& v = kv.second;
    const std::string where = file + ":" + std::to_string(v.Mark().line + 1) + ": box of '" +
                              name + "'";
    if (!v.IsSequence() || v.size() != 4) throw IoError(where + " must be [u0, v0, u1, v1]");
    std::array<double, 4> b{};
    for (std::size_t k = 0; k < 4; ++k) {
      const std::string s = v[k].IsScalar() ? v[k].Scalar() : "";
      char* end = nullptr;
      b[k] = std::strtod(s.c_str(), &end);
      if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(b[k]))
        throw IoError(where + " holds '" + s + "', not a number");
    }
    if (!(b[2] > b[0] && b[3] > b[1])) throw IoError(where + " must have u1 > u0 and v1 > v0");
    boxes[name] = b;
  }
  return boxes;
}

std::map<std::string, std::array<double, 4>> ReadBoxes(const std::string& path) {
  return ParseBoxes(ReadFile(path, kMaxYamlBytes), path);
}

}  // namespace depthbias::io
