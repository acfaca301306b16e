#include "io/csv.h"

#include <charconv>
#include <cmath>
#include <limits>
#include <set>

#include "io/atomic_file.h"

namespace depthbias::io {
namespace {

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}

bool IsMissingText(const std::string& t) {
  return t.empty() || t == "nan" || t == "NaN" || t == "NAN" || t == "-" || t == "NA";
}

// Splits the text into records of fields; records[i].second is the line it started on.
std::vector<std::pair<std::vector<std::string>, int>> Tokenize(const std::string& text,
                                                               const std::string& file) {
  std::vector<std::pair<std::vector<std::string>, int>> records;
  size_t i = 0;
  if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) i = 3;
  int line = 1;
  std::vector<std::string> fields;
  std::string field;
  bool any = false;       // anything on this record yet
  bool was_quoted = false;
  int record_line = 1;
  auto end_field = [&]() {
    fields.push_back(was_quoted ? field : Trim(field));
    field.clear();
    was_quoted = false;
  };
  auto end_record = [&]() {
    if (any) {
      end_field();
      records.emplace_back(std::move(fields), record_line);
    }
    fields.clear();
    field.clear();
    any = false;
    was_quoted = false;
  };
  while (i < text.size()) {
    const char c = text[i];
    if (!any) record_line = line;
    if (c == '"' && Trim(field).empty() && !was_quoted) {
      // Quoted field.
      any = true;
      was_quoted = true;
      field.clear();
      const int open_line = line;
      ++i;
      bool closed = false;
      while (i < text.size()) {
        if (text[i] == '"') {
          if (i + 1 < text.size() && text[i + 1] == '"') {
            field.push_back('"');
            i += 2;
            continue;
          }
          closed = true;
          ++i;
          break;
        }
        if (text[i] == '\n') ++line;
        field.push_back(text[i]);
        ++i;
      }
      if (!closed) {
        throw IoError(file + ":" + std::to_string(open_line) + ": unterminated quoted field");
      }
      // Only spaces may follow up to the next separator.
      while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
      if (i < text.size() && text[i] != ',' && text[i] != '\n' && text[i] != '\r') {
        throw IoError(file + ":" + std::to_string(line) +
                      ": unexpected text after a closing quote");
      }
      continue;
    }
    if (c == ',') {
      any = true;
      end_field();
      ++i;
    } else if (c == '\r' || c == '\n') {
      end_record();
      if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
      ++i;
      ++line;
    } else {
      if (was_quoted) {
        throw IoError(file + ":" + std::to_string(line) +
                      ": unexpected text after a closing quote");
      }
      if (c != ' ' && c != '\t') any = true;
      field.push_back(c);
      ++i;
    }
  }
  end_record();
  return records;
}

}  // namespace

int CsvTable::Column(const std::string& name) const {
  for (size_t i = 0; i < header.size(); ++i) {
    if (header[i] == name) return static_cast<int>(i);
  }
  return -1;
}

int CsvTable::RequireColumn(const std::string& name) const {
  const int c = Column(name);
  if (c < 0) throw IoError(file + ": missing required column '" + name + "'");
  return c;
}

const std::string& CsvTable::Cell(size_t row, int col) const {
  static const std::string kEmpty;
  if (col < 0) return kEmpty;
  return rows.at(row).at(static_cast<size_t>(col));
}

std::string CsvTable::Where(size_t row) const {
  return file + ":" + std::to_string(row < lines.size() ? lines[row] : 0);
}

double CsvTable::Number(size_t row, int col) const {
  const std::string& t = Cell(row, col);
  if (IsMissingText(t)) return std::numeric_limits<double>::quiet_NaN();
  double value = 0.0;
  const char* first = t.data();
  const char* last = t.data() + t.size();
  if (*first == '+') ++first;
  const auto res = std::from_chars(first, last, value);
  if (res.ec != std::errc() || res.ptr != last) {
    throw IoError(Where(row) + ": column '" + header[static_cast<size_t>(col)] + "': '" + t +
                  "' is not a number");
  }
  if (std::isinf(value)) {
    throw IoError(Where(row) + ": column '" + header[static_cast<size_t>(col)] + "': '" + t +
                  "' is not a finite number");
  }
  return value;
}

double CsvTable::RequiredNumber(size_t row, int col) const {
  const double v = Number(row, col);
  if (std::isnan(v)) {
    const std::string& t = Cell(row, col);
    throw IoError(Where(row) + ": column '" + header[static_cast<size_t>(col)] + "': " +
                  (t.empty() ? std::string("empty") : "'" + t + "'") +
                  ", a number is required");
  }
  return v;
}

CsvTable ParseCsv(const std::string& text, const std::string& file) {
  auto records = Tokenize(text, file);
  CsvTable table;
  table.file = file;
  if (records.empty()) throw IoError(file + ": empty file, a CSV header is required");
  table.header = records.front().first;
  std::set<std::string> seen;
  for (size_t c = 0; c < table.header.size(); ++c) {
    const std::string& name = table.header[c];
    if (name.empty()) {
      throw IoError(file + ":" + std::to_string(records.front().second) + ": column " +
                    std::to_string(c + 1) + " has an empty name");
    }
    if (!seen.insert(name).second) {
      throw IoError(file + ":" + std::to_string(records.front().second) +
                    ": column '" + name + "' appears twice");
    }
  }
  for (size_t r = 1; r < records.size(); ++r) {
    auto& [fields, line] = records[r];
    if (fields.size() != table.header.size()) {
      throw IoError(file + ":" + std::to_string(line) + ": " + std::to_string(fields.size()) +
                    " cells, the header has " + std::to_string(table.header.size()));
    }
    table.rows.push_back(std::move(fields));
    table.lines.push_back(line);
  }
  return table;
}

CsvTable ReadCsv(const std::string& path) { return ParseCsv(ReadFile(path), path); }

std::string CsvField(const std::string& text) {
  // Quoted when the reader would otherwise split it or trim it (spaces and tabs at either end).
  const auto blank = [](char c) { return c == ' ' || c == '\t'; };
  const bool quote = text.find_first_of(",\"\n\r") != std::string::npos ||
                     (!text.empty() && (blank(text.front()) || blank(text.back())));
  if (!quote) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += "\"\"";
    else out.push_back(c);
  }
  out += "\"";
  return out;
}

std::string CsvNumber(double value) {
  if (std::isnan(value)) return "";
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), value);
  return std::string(buf, res.ptr);
}

std::string FormatCsv(const std::vector<std::string>& header,
                      const std::vector<std::vector<std::string>>& rows) {
  std::string out;
  auto put = [&out](const std::vector<std::string>& cells) {
    for (size_t i = 0; i < cells.size(); ++i) {
      if (i) out.push_back(',');
      out += CsvField(cells[i]);
    }
    out.push_back('\n');
  };
  put(header);
  for (const auto& r : rows) {
    if (r.size() != header.size()) {
      throw std::invalid_argument("FormatCsv: a row has " + std::to_string(r.size()) +
                                  " cells, the header " + std::to_string(header.size()));
    }
    put(r);
  }
  return out;
}

void WriteCsv(const std::string& path, const std::vector<std::string>& header,
              const std::vector<std::vector<std::string>>& rows) {
  WriteFileAtomic(path, FormatCsv(header, rows));
}

}  // namespace depthbias::io
