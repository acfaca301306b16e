#include "io/yaml_limits.h"

#include <new>
#include <utility>
#include <vector>

#include "io/atomic_file.h"
#include "records/number_text.h"

namespace depthbias::io {
namespace {

// Walks the document as a reader would (aliases expanded), depth-first with an explicit
// stack, and stops at the first limit passed.
void CheckTree(const YAML::Node& root, const std::string& file) {
  std::vector<std::pair<YAML::Node, int>> stack = {{root, 1}};
  std::size_t visited = 0;
  while (!stack.empty()) {
    const auto [node, depth] = stack.back();
    stack.pop_back();
    if (++visited > kMaxYamlNodes)
      throw IoError(file + ": more than " + std::to_string(kMaxYamlNodes) +
                    " values once its aliases (*name) are expanded; refused");
    if (depth > kMaxYamlDepth)
      throw IoError(file + ":" + std::to_string(node.Mark().line + 1) + ": nested deeper than " +
                    std::to_string(kMaxYamlDepth) + " levels; refused");
    if (node.IsMap()) {
      for (const auto& kv : node) {
        stack.emplace_back(kv.first, depth + 1);
        stack.emplace_back(kv.second, depth + 1);
      }
    } else if (node.IsSequence()) {
      for (const auto& child : node) stack.emplace_back(child, depth + 1);
    }
  }
}

}  // namespace

YAML::Node LoadYaml(const std::string& text, const std::string& file) {
  if (text.size() > kMaxYamlBytes)
    throw IoError(file + ": " + records::BytesText(static_cast<double>(text.size())) +
                  ", more than the " + records::BytesText(static_cast<double>(kMaxYamlBytes)) +
                  " a YAML input may be");
  YAML::Node root;
  try {
    root = YAML::Load(text);
    CheckTree(root, file);
  } catch (const YAML::Exception& e) {
    throw IoError(file + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML/JSON: " +
                  e.msg);
  } catch (const std::bad_alloc&) {
    throw IoError(file + ": out of memory while reading it; refused");
  }
  return root;
}

void CheckYamlText(const std::string& text, const std::string& file) { LoadYaml(text, file); }

std::string ReadYamlFile(const std::string& path) {
  std::string text = ReadFile(path, kMaxYamlBytes);
  CheckYamlText(text, path);
  return text;
}

}  // namespace depthbias::io
