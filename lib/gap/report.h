#pragma once
// The diagnosis as text: gap.json (machine-readable; its schema is in the README) and report.md
// (for a safety engineer), and a few lines for a terminal. The library writes no file: the app
// hands these texts to io.

#include <cstdint>
#include <string>

#include "gap/diagnose.h"

namespace depthbias::gap {

struct ReportContext {
  std::string input;         // the real table's file name
  std::string input_sha256;  // its digest
  std::string protocol;      // protocol and sensor files used
  std::string sensor;
  std::uint64_t seed = 1;
  std::string version;
};

std::string GapJson(const DiagnoseResult& result, const DiagnoseParams& params,
                    const ReportContext& context);
std::string GapMarkdown(const DiagnoseResult& result, const DiagnoseParams& params,
                        const ReportContext& context);
// Where, which, how far, what is left: four to six lines.
std::string GapSummary(const DiagnoseResult& result);

}  // namespace depthbias::gap
