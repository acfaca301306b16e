#pragma once
// A small CSV table: one header row, then data rows (RFC 4180 quoting: fields with commas,
// quotes or line breaks are quoted, quotes doubled). Empty cells and "nan" read as NaN where a
// number is asked for. Errors name the file, the line and the column.

#include <string>
#include <vector>

#include "io/io_error.h"

namespace depthbias::io {

struct CsvTable {
  std::string file;                              // name used in error messages
  std::vector<std::string> header;               // column names, trimmed
  std::vector<std::vector<std::string>> rows;    // each exactly header.size() cells
  std::vector<int> lines;                        // 1-based line where each row starts

  // Index of a column, or -1.
  int Column(const std::string& name) const;
  // Index of a column; throws IoError "<file>: missing required column '<name>'".
  int RequireColumn(const std::string& name) const;

  // Cell text of row `row` in column `col` (col may be -1: then "").
  const std::string& Cell(size_t row, int col) const;
  // Cell as a number: empty, "nan", "NaN", "-" and "NA" give NaN; anything else that is not a
  // whole number throws IoError "<file>:<line>: column '<name>': '<text>' is not a number".
  double Number(size_t row, int col) const;
  // Like Number but NaN is an error too ("... is empty/NaN, a number is required").
  double RequiredNumber(size_t row, int col) const;
  // "<file>:<line>" of a row, for callers' own messages.
  std::string Where(size_t row) const;
};

// Parses CSV text; `file` names it in errors. Blank lines are skipped; a row with another
// number of cells than the header throws IoError naming the line. A UTF-8 BOM and CRLF line
// ends are accepted. Duplicate or empty column names throw.
CsvTable ParseCsv(const std::string& text, const std::string& file);
// Reads and parses a CSV file (IoError if missing or malformed).
CsvTable ReadCsv(const std::string& path);

// One CSV field, quoted only if it must be.
std::string CsvField(const std::string& text);
// A number in the shortest text that reads back to the same double; NaN → "" (empty cell).
std::string CsvNumber(double value);
// The table as CSV text (header, then rows; "\n" line ends).
std::string FormatCsv(const std::vector<std::string>& header,
                      const std::vector<std::vector<std::string>>& rows);
// Writes a table atomically (temp file + rename).
void WriteCsv(const std::string& path, const std::vector<std::string>& header,
              const std::vector<std::vector<std::string>>& rows);

}  // namespace depthbias::io
