#pragma once
// Formatting shared by the gap module's text: the report, the headline and the reasons
// the selection gives (private to the gap module).

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "gap/diagnose.h"

namespace depthbias::gap::text {

inline std::string Num(double v, int digits = 3) {
  if (!std::isfinite(v)) return "–";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

inline std::string Signed(double v, int digits = 3) {
  return (std::isfinite(v) && v > 0 ? "+" : "") + Num(v, digits);
}

inline std::string Pct(double v) {
  if (!std::isfinite(v)) return "–";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f %%", v);
  return buf;
}

// A Markdown table of gaps, mean z² over all metrics and per compared metric: its header (first
// column `first`), then one row a GapStat.
inline std::string GapTableHeader(const std::string& first,
                                  const std::vector<std::string>& metrics) {
  std::string h = "| " + first + " | all metrics |";
  for (const std::string& m : metrics) h += " " + m + " |";
  h += "\n|---|---|";
  for (size_t k = 0; k < metrics.size(); ++k) h += "---|";
  return h + "\n";
}
inline std::string GapTableRow(const std::string& name, const GapStat& g, size_t metrics) {
  std::string row = "| " + name + " | " + Num(g.overall) + " |";
  for (size_t k = 0; k < metrics && k < g.mean_sq.size(); ++k)
    row += " " + Num(g.mean_sq[k]) + " |";
  return row + "\n";
}

// A term's parameters: "p v, q w" (per scenario "S: …; T: …"), with 95 % intervals and a
// "(grid edge)" mark on request (a discrete axis's profiled interval always); with hide_edges a
// value on the grid's edge is not given (it is no measurement) but said to be there.
std::string ParamsText(const DiagnoseResult& r, const TermFit& t, bool with_ci,
                       bool hide_edges = false);

// " (a width's interval: …)" where a selected term's width was profiled, else empty.
std::string WidthIntervalNote(const DiagnoseResult& r);

// The headline for a safety engineer: range error in metres and its direction, placement,
// emitter, what is selected or unexplained, the nested simulated shrink.
std::string Headline(const DiagnoseResult& r);
// The report's sections on placement, emitter, nested hold-out, ambiguity and the open world.
std::string EvidenceMarkdown(const DiagnoseResult& r, const DiagnoseParams& p);

}  // namespace depthbias::gap::text
