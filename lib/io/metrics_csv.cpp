#include "io/metrics_csv.h"

#include <cmath>

#include "io/atomic_file.h"
#include "io/csv.h"
#include "io/ranges.h"

namespace depthbias::io {
namespace {

using records::PanelMetrics;

struct NumberColumn {
  const char* name;
  double PanelMetrics::*field;
  NumberRule rule;  // io/ranges.h: the same rules as every other reader
};

// Numeric columns in DESIGN.md's order, after the four text columns.
const NumberColumn kNumbers[] = {
    {"distance_m", &PanelMetrics::distance_m, rules::kDistanceM},
    {"angle_deg", &PanelMetrics::angle_deg, rules::kAngleDeg},
    {"frames", &PanelMetrics::frames, rules::kCount},
    {"mean_m", &PanelMetrics::mean_m, rules::kDistanceM},
    {"median_m", &PanelMetrics::median_m, rules::kDistanceM},
    {"plane_std_m", &PanelMetrics::plane_std_m, rules::kSpreadM},
    {"hole_rate_pct", &PanelMetrics::hole_rate_pct, rules::kPercent},
    {"valid_pct", &PanelMetrics::valid_pct, rules::kPercent},
    {"range_m", &PanelMetrics::range_m, rules::kDistanceM},
    {"azimuth_deg", &PanelMetrics::azimuth_deg, rules::kDirectionDeg},
    {"elevation_deg", &PanelMetrics::elevation_deg, rules::kDirectionDeg},
    {"normal_tilt_deg", &PanelMetrics::normal_tilt_deg, rules::kTiltDeg},
    {"panel_width_m", &PanelMetrics::panel_width_m, rules::kSpreadM},
    {"panel_height_m", &PanelMetrics::panel_height_m, rules::kSpreadM},
    {"region_px", &PanelMetrics::region_px, rules::kCount},
    {"subpixel_rms_px", &PanelMetrics::subpixel_rms_px, rules::kNonNegative},
    {"temporal_std_m", &PanelMetrics::temporal_std_m, rules::kSpreadM},
    {"sigma_d_px", &PanelMetrics::sigma_d_px, rules::kNonNegative},
};
constexpr int kArticleNumbers = 8;  // distance_m … valid_pct

std::string TrimBlanks(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

}  // namespace

const std::vector<std::string>& MetricsColumns() {
  static const std::vector<std::string> columns = [] {
    std::vector<std::string> c = {"bag", "light", "emitter", "preset"};
    for (const auto& n : kNumbers) c.push_back(n.name);
    c.push_back("status");
    c.push_back("message");
    return c;
  }();
  return columns;
}

std::vector<PanelMetrics> ParseMetricsCsv(const std::string& text, const std::string& file) {
  const CsvTable t = ParseCsv(text, file);
  const int bag = t.RequireColumn("bag");
  const int light = t.RequireColumn("light");
  const int emitter = t.RequireColumn("emitter");
  const int preset = t.RequireColumn("preset");
  std::vector<int> num_col;
  for (int i = 0; i < static_cast<int>(std::size(kNumbers)); ++i) {
    num_col.push_back(i < kArticleNumbers ? t.RequireColumn(kNumbers[i].name)
                                          : t.Column(kNumbers[i].name));
  }
  const int status = t.Column("status");
  const int message = t.Column("message");
  std::vector<PanelMetrics> out;
  out.reserve(t.rows.size());
  for (size_t r = 0; r < t.rows.size(); ++r) {
    PanelMetrics m;
    m.bag = t.Cell(r, bag);
    m.light = t.Cell(r, light);
    m.emitter = t.Cell(r, emitter);
    m.preset = t.Cell(r, preset);
    // The status decides which columns a row must have: read without the blanks a quoted cell
    // keeps, so that "ok " is an ok row (and needs its median) like ok.
    const std::string status_text = TrimBlanks(t.Cell(r, status));
    if (!status_text.empty()) m.status = status_text;
    m.message = t.Cell(r, message);
    for (size_t i = 0; i < num_col.size(); ++i) {
      if (num_col[i] < 0) continue;
      const std::string name = kNumbers[i].name;
      // Ground truth (distance_m, angle_deg) may be empty: panel_extract run without a manifest
      // measures a recording it knows nothing about. Fitting skips such rows.
      const bool required = m.ok() && (name == "median_m" || name == "mean_m");
      const double v = required ? t.RequiredNumber(r, num_col[i]) : t.Number(r, num_col[i]);
      if (!std::isnan(v)) {
        const std::string why = kNumbers[i].rule.Why(v);
        if (!why.empty()) throw IoError(t.Where(r) + ": column '" + name + "': " + why);
      }
      m.*(kNumbers[i].field) = v;
    }
    if (m.bag.empty()) throw IoError(t.Where(r) + ": column 'bag': empty");
    out.push_back(std::move(m));
  }
  return out;
}

std::vector<PanelMetrics> ReadMetricsCsv(const std::string& path) {
  return ParseMetricsCsv(ReadFile(path), path);
}

std::vector<std::string> MetricsCells(const PanelMetrics& m) {
  std::vector<std::string> cells = {m.bag, m.light, m.emitter, m.preset};
  for (const auto& n : kNumbers) cells.push_back(CsvNumber(m.*(n.field)));
  cells.push_back(m.status);
  cells.push_back(m.message);
  return cells;
}

std::string FormatMetricsCsv(const std::vector<PanelMetrics>& rows) {
  std::vector<std::vector<std::string>> cells;
  cells.reserve(rows.size());
  for (const auto& m : rows) cells.push_back(MetricsCells(m));
  return FormatCsv(MetricsColumns(), cells);
}

void WriteMetricsCsv(const std::string& path, const std::vector<PanelMetrics>& rows) {
  WriteFileAtomic(path, FormatMetricsCsv(rows));
}

}  // namespace depthbias::io
