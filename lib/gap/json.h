#pragma once
// A small JSON text builder for the gap report: objects and arrays opened and closed in order,
// strings escaped, numbers with 6 significant digits (non-finite numbers as null). The caller
// keeps the nesting right; Text() returns the document.

#include <string>
#include <vector>

namespace depthbias::gap {

class JsonWriter {
 public:
  JsonWriter& BeginObject(const std::string& key = "");
  JsonWriter& EndObject();
  JsonWriter& BeginArray(const std::string& key = "");
  JsonWriter& EndArray();
  JsonWriter& Number(const std::string& key, double value);
  JsonWriter& Number(double value) { return Number("", value); }
  JsonWriter& Integer(const std::string& key, long long value);
  JsonWriter& String(const std::string& key, const std::string& value);
  JsonWriter& String(const std::string& value) { return String("", value); }
  JsonWriter& Bool(const std::string& key, bool value);
  JsonWriter& Null(const std::string& key);
  const std::string& Text() const { return out_; }

  static std::string Escape(const std::string& s);
  static std::string FormatNumber(double v);

 private:
  void Prefix(const std::string& key);
  std::string out_;
  std::vector<bool> first_;  // per open container: nothing written in it yet
};

}  // namespace depthbias::gap
