// gap.json read back (json_read.h).
#include "gap/json_read.h"

#include <cstdlib>

namespace depthbias::gap {
namespace {

class Parser {
 public:
  explicit Parser(const std::string& s) : s_(s) {}
  bool Parse(JsonValue* out) {
    if (!Value(out, 0)) return false;
    Space();
    return i_ == s_.size();
  }

 private:
  void Space() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\n' || s_[i_] == '\t' || s_[i_] == '\r'))
      ++i_;
  }
  bool Literal(const char* word) {
    const std::string w(word);
    if (s_.compare(i_, w.size(), w) != 0) return false;
    i_ += w.size();
    return true;
  }
  bool String(std::string* out) {
    if (s_[i_] != '"') return false;
    for (++i_; i_ < s_.size(); ++i_) {
      const char c = s_[i_];
      if (c == '"') {
        ++i_;
        return true;
      }
      if (c != '\\') {
        *out += c;
        continue;
      }
      if (++i_ >= s_.size()) return false;
      switch (s_[i_]) {
        case 'n': *out += '\n'; break;
        case 't': *out += '\t'; break;
        case 'r': *out += '\r'; break;
        case 'b': *out += '\b'; break;
        case 'f': *out += '\f'; break;
        case 'u': {  // the writer escapes control characters only
          if (i_ + 4 >= s_.size()) return false;
          *out += static_cast<char>(std::strtol(s_.substr(i_ + 1, 4).c_str(), nullptr, 16));
          i_ += 4;
          break;
        }
        default: *out += s_[i_];
      }
    }
    return false;
  }
  bool Value(JsonValue* v, int depth) {
    Space();
    if (i_ >= s_.size() || depth > 64) return false;
    const char c = s_[i_];
    if (c == '{' || c == '[') {
      v->type = c == '{' ? JsonValue::kObject : JsonValue::kArray;
      ++i_;
      Space();
      if (i_ < s_.size() && s_[i_] == (c == '{' ? '}' : ']')) {
        ++i_;
        return true;
      }
      while (true) {
        Space();
        JsonValue item;
        std::string key;
        if (c == '{') {
          if (i_ >= s_.size() || !String(&key)) return false;
          Space();
          if (i_ >= s_.size() || s_[i_++] != ':') return false;
        }
        if (!Value(&item, depth + 1)) return false;
        if (c == '{') {
          v->members.emplace_back(key, std::move(item));
        } else {
          v->items.push_back(std::move(item));
        }
        Space();
        if (i_ >= s_.size()) return false;
        const char next = s_[i_++];
        if (next == ',') continue;
        return next == (c == '{' ? '}' : ']');
      }
    }
    if (c == '"') return v->type = JsonValue::kString, String(&v->text);
    if (Literal("null")) return v->type = JsonValue::kNull, true;
    if (Literal("true")) return v->type = JsonValue::kBool, v->number = 1, true;
    if (Literal("false")) return v->type = JsonValue::kBool, v->number = 0, true;
    char* end = nullptr;
    v->number = std::strtod(s_.c_str() + i_, &end);
    if (end == s_.c_str() + i_) return false;
    v->type = JsonValue::kNumber;
    i_ = static_cast<size_t>(end - s_.c_str());
    return true;
  }
  const std::string& s_;
  size_t i_ = 0;
};

}  // namespace

bool ParseJson(const std::string& text, JsonValue* out) { return Parser(text).Parse(out); }

}  // namespace depthbias::gap
