#pragma once
// The project's one JSON text builder (gap.json, the detections JSONL): objects and arrays
// opened and closed in order, strings escaped, numbers with 6 significant digits unless asked
// for more (non-finite numbers as null; never truncated: 1e308 stays 1e+308). Indented over
// several lines, or on one line (a JSONL record). The caller keeps the nesting right; Text()
// returns the document, which ends with "\n" once the outermost container is closed.

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace depthbias::records {

class JsonWriter {
 public:
  enum class Layout { kIndented, kOneLine };
  explicit JsonWriter(Layout layout = Layout::kIndented) : one_line_(layout == Layout::kOneLine) {}

  JsonWriter& BeginObject(const std::string& key = "") { return Open(key, '{'); }
  JsonWriter& EndObject() { return Close('}'); }
  JsonWriter& BeginArray(const std::string& key = "") { return Open(key, '['); }
  JsonWriter& EndArray() { return Close(']'); }
  // `digits` significant digits (6 by default; 15 keeps a timestamp's microseconds).
  JsonWriter& Number(const std::string& key, double value, int digits = 6) {
    Prefix(key);
    out_ += FormatNumber(value, digits);
    return *this;
  }
  JsonWriter& Number(double value) { return Number("", value); }
  JsonWriter& Integer(const std::string& key, long long value) {
    Prefix(key);
    out_ += std::to_string(value);
    return *this;
  }
  JsonWriter& String(const std::string& key, const std::string& value) {
    Prefix(key);
    out_ += Escape(value);
    return *this;
  }
  JsonWriter& String(const std::string& value) { return String("", value); }
  JsonWriter& Bool(const std::string& key, bool value) {
    Prefix(key);
    out_ += value ? "true" : "false";
    return *this;
  }
  JsonWriter& Null(const std::string& key) {
    Prefix(key);
    out_ += "null";
    return *this;
  }
  const std::string& Text() const { return out_; }

  static std::string Escape(const std::string& s) {
    std::string o = "\"";
    for (unsigned char c : s) {
      switch (c) {
        case '"': o += "\\\""; break;
        case '\\': o += "\\\\"; break;
        case '\n': o += "\\n"; break;
        case '\t': o += "\\t"; break;
        case '\r': o += "\\r"; break;
        default:
          if (c < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", c);
            o += buf;
          } else {
            o += static_cast<char>(c);
          }
      }
    }
    return o + "\"";
  }
  // %.<digits>g: at most 24 characters for any double and digits ≤ 17, so the buffer holds it.
  static std::string FormatNumber(double v, int digits = 6) {
    if (!std::isfinite(v)) return "null";
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.*g", digits < 1 ? 1 : digits > 17 ? 17 : digits, v);
    return buf;
  }

 private:
  void Prefix(const std::string& key) {
    if (!first_.empty()) {
      if (!first_.back()) out_ += one_line_ ? ", " : ",";
      first_.back() = false;
      if (!one_line_) out_ += "\n" + std::string(2 * first_.size(), ' ');
    }
    if (!key.empty()) out_ += Escape(key) + ": ";
  }
  JsonWriter& Open(const std::string& key, char bracket) {
    Prefix(key);
    out_ += bracket;
    first_.push_back(true);
    return *this;
  }
  JsonWriter& Close(char bracket) {
    const bool empty = first_.back();
    first_.pop_back();
    if (!empty && !one_line_) out_ += "\n" + std::string(2 * first_.size(), ' ');
    out_ += bracket;
    if (first_.empty()) out_ += "\n";
    return *this;
  }

  bool one_line_;
  std::string out_;
  std::vector<bool> first_;  // per open container: nothing written in it yet
};

}  // namespace depthbias::records
