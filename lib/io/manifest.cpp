#include "io/manifest.h"

#include <cmath>
#include <filesystem>

#include "io/atomic_file.h"
#include "io/csv.h"
#include "io/ranges.h"

namespace depthbias::io {

namespace {

namespace fs = std::filesystem;

// Absolute and normalized; links resolved as far as the path exists.
std::string Resolved(const fs::path& p) {
  std::error_code ec;
  fs::path abs = fs::absolute(p, ec);
  if (ec) abs = p;
  const fs::path canon = fs::weakly_canonical(abs, ec);
  return (ec ? abs.lexically_normal() : canon).string();
}

}  // namespace

Manifest::Manifest(std::string file, std::vector<ManifestRow> rows,
                   std::vector<std::string> extra_columns)
    : file_(std::move(file)), rows_(std::move(rows)), extra_columns_(std::move(extra_columns)) {
  for (size_t i = 0; i < rows_.size(); ++i) {
    const auto [it, fresh] = by_path_.emplace(PathOf(rows_[i]), i);
    if (!fresh) {
      throw IoError(file_ + ":" + std::to_string(rows_[i].line) + ": bag '" + rows_[i].bag +
                    "' already listed on line " + std::to_string(rows_[it->second].line) +
                    " (as '" + rows_[it->second].bag + "')");
    }
  }
}

std::string Manifest::PathOf(const ManifestRow& row) const {
  const fs::path bag(row.bag);
  return Resolved(bag.is_absolute() ? bag : fs::path(file_).parent_path() / bag);
}

const ManifestRow* Manifest::Find(const std::string& bag_path) const {
  const auto it = by_path_.find(Resolved(bag_path));
  return it == by_path_.end() ? nullptr : &rows_[it->second];
}

Manifest ParseManifest(const std::string& text, const std::string& file) {
  const CsvTable t = ParseCsv(text, file);
  const int bag = t.RequireColumn("bag");
  const int distance = t.RequireColumn("distance_m");
  const int angle = t.RequireColumn("angle_deg");
  const int light = t.RequireColumn("light");
  const int preset = t.Column("preset");
  const int emitter = t.Column("emitter");
  std::vector<std::string> extras;
  std::vector<int> extra_cols;
  for (size_t c = 0; c < t.header.size(); ++c) {
    const int ci = static_cast<int>(c);
    if (ci == bag || ci == distance || ci == angle || ci == light || ci == preset ||
        ci == emitter) {
      continue;
    }
    extras.push_back(t.header[c]);
    extra_cols.push_back(ci);
  }
  std::vector<ManifestRow> rows;
  for (size_t r = 0; r < t.rows.size(); ++r) {
    ManifestRow m;
    m.line = t.lines[r];
    m.bag = t.Cell(r, bag);
    if (m.bag.empty()) throw IoError(t.Where(r) + ": column 'bag': empty");
    m.distance_m = t.RequiredNumber(r, distance);
    if (const std::string why = rules::kDistanceM.Why(m.distance_m); !why.empty())
      throw IoError(t.Where(r) + ": column 'distance_m': " + why);
    m.angle_deg = t.RequiredNumber(r, angle);
    if (const std::string why = rules::kAngleDeg.Why(m.angle_deg); !why.empty())
      throw IoError(t.Where(r) + ": column 'angle_deg': " + why);
    m.light = t.Cell(r, light);
    if (m.light.empty()) throw IoError(t.Where(r) + ": column 'light': empty");
    if (preset >= 0 && !t.Cell(r, preset).empty()) m.preset = t.Cell(r, preset);
    if (emitter >= 0 && !t.Cell(r, emitter).empty()) {
      const std::string& e = t.Cell(r, emitter);
      if (e != "on" && e != "off") {
        throw IoError(t.Where(r) + ": column 'emitter': '" + e + "', expected on or off");
      }
      m.emitter = e;
    }
    for (size_t i = 0; i < extras.size(); ++i) m.extras[extras[i]] = t.Cell(r, extra_cols[i]);
    rows.push_back(std::move(m));
  }
  return Manifest(file, std::move(rows), std::move(extras));
}

Manifest ReadManifest(const std::string& path) { return ParseManifest(ReadFile(path), path); }

std::string FormatManifest(const std::vector<ManifestRow>& rows,
                           const std::vector<std::string>& extra_columns) {
  std::vector<std::string> header = {"bag", "distance_m", "angle_deg", "light", "preset",
                                     "emitter"};
  header.insert(header.end(), extra_columns.begin(), extra_columns.end());
  std::vector<std::vector<std::string>> cells;
  for (const auto& m : rows) {
    std::vector<std::string> c = {m.bag, CsvNumber(m.distance_m), CsvNumber(m.angle_deg),
                                  m.light, m.preset.value_or(""), m.emitter.value_or("")};
    for (const auto& e : extra_columns) {
      const auto it = m.extras.find(e);
      c.push_back(it == m.extras.end() ? "" : it->second);
    }
    cells.push_back(std::move(c));
  }
  return FormatCsv(header, cells);
}

void WriteManifest(const std::string& path, const std::vector<ManifestRow>& rows,
                   const std::vector<std::string>& extra_columns) {
  WriteFileAtomic(path, FormatManifest(rows, extra_columns));
}

}  // namespace depthbias::io
