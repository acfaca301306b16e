// libFuzzer target: any text as a panel-metrics CSV. Parsing either succeeds or throws IoError;
// a table that parses is written back and must read back the same (round trip), and every
// number in it lies in its column's range (io/ranges.h).
#include <cmath>
#include <cstdint>
#include <string>

#include "io/io_error.h"
#include "io/metrics_csv.h"

namespace {

bool Same(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::vector<depthbias::records::PanelMetrics> rows;
  try {
    rows = depthbias::io::ParseMetricsCsv(text, "fuzz.csv");
  } catch (const depthbias::io::IoError&) {
    return 0;
  }
  for (const auto& r : rows) {
    if (r.ok() && !(r.median_m > 0 && r.median_m <= 1000)) __builtin_trap();
    if (!std::isnan(r.angle_deg) && !(std::fabs(r.angle_deg) < 90)) __builtin_trap();
  }
  const auto back =
      depthbias::io::ParseMetricsCsv(depthbias::io::FormatMetricsCsv(rows), "round-trip.csv");
  if (back.size() != rows.size()) __builtin_trap();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& a = rows[i];
    const auto& b = back[i];
    if (a.bag != b.bag || a.light != b.light || a.status != b.status || a.message != b.message ||
        !Same(a.median_m, b.median_m) || !Same(a.distance_m, b.distance_m) ||
        !Same(a.angle_deg, b.angle_deg) || !Same(a.temporal_std_m, b.temporal_std_m) ||
        !Same(a.sigma_d_px, b.sigma_d_px))
      __builtin_trap();
  }
  return 0;
}
