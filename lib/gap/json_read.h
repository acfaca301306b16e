#pragma once
// gap.json read back: a JSON value and a small recursive-descent parser (the files are ours and
// small: no streaming). The judge of the withheld cases reads what a diagnosis published.

#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace depthbias::gap {

struct JsonValue {
  enum Type { kNull, kBool, kNumber, kString, kArray, kObject } type = kNull;
  double number = NAN;
  std::string text;
  std::vector<JsonValue> items;
  std::vector<std::pair<std::string, JsonValue>> members;

  const JsonValue* Find(const std::string& key) const {
    for (const auto& [k, v] : members)
      if (k == key) return &v;
    return nullptr;
  }
  // The number `key` holds, or NaN (no such key, or not a number).
  double Number(const std::string& key) const {
    const JsonValue* v = Find(key);
    return v && v->type == kNumber ? v->number : NAN;
  }
  bool empty() const {
    return type == kNull || (type == kArray && items.empty()) ||
           (type == kObject && members.empty()) || (type == kString && text.empty());
  }
};


// Parses the whole of `text` into *out; false on malformed JSON or trailing content.
bool ParseJson(const std::string& text, JsonValue* out);

}  // namespace depthbias::gap
