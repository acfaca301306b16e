#pragma once
// The panel-metrics CSV of DESIGN.md: one row per recording, columns in DESIGN.md's order.
// Reading accepts the article's 12-column table (the extra columns then read as NaN) and
// ignores columns it does not know.

#include <string>
#include <vector>

#include "records/panel_metrics.h"
#include "io/io_error.h"

namespace depthbias::io {

// Column names in DESIGN.md's order.
const std::vector<std::string>& MetricsColumns();

// Required columns: bag, light, emitter, preset, distance_m, angle_deg, frames, mean_m,
// median_m, plane_std_m, hole_rate_pct, valid_pct (the article's twelve). distance_m and
// angle_deg must be numbers in every row; median_m and mean_m in every row whose status is
// "ok" (a missing status column means "ok"). Any other numeric cell may be empty (NaN).
// A number present must lie in its column's range (io/ranges.h, the rules the manifest and the
// weights YAML follow too): distances, depths and ranges in (0, 1000] m, angle_deg in
// (-90, 90), percentages in [0, 100], spreads and counts >= 0, counts whole.
// Throws IoError naming the file, the line and the column.
std::vector<records::PanelMetrics> ParseMetricsCsv(const std::string& text,
                                                  const std::string& file);
std::vector<records::PanelMetrics> ReadMetricsCsv(const std::string& path);

// All columns of DESIGN.md, NaN as empty cells.
std::string FormatMetricsCsv(const std::vector<records::PanelMetrics>& rows);
void WriteMetricsCsv(const std::string& path, const std::vector<records::PanelMetrics>& rows);

// Header and cells of the rows, for tools that append their own columns (correct_depth).
std::vector<std::string> MetricsCells(const records::PanelMetrics& row);

}  // namespace depthbias::io
