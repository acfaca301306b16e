#pragma once
// Proof on data whose answer is known: the protocol simulated with an effect the base model
// lacks (each registered effect at a small but real size and a large one), then diagnosed with
// the base model. The effect must rank first (or be named within a pair reported as confounded,
// or be reported as confounded with the calibration), its parameters come back within 20 % of
// their departure from the neutral value, and the held-out gap shrink by at least 70 %.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "gap/diagnose.h"

namespace depthbias::gap {

struct WithheldCase {
  std::string effect;
  std::string size;  // "small", "large"
  std::map<std::string, double> params;
};

// Every effect of the registry at two sizes.
std::vector<WithheldCase> DefaultWithheldCases();

struct CaseOutcome {
  WithheldCase truth;
  int rank = 0;               // of the effect among the candidates alone (1 = first)
  std::string top;            // the first-ranked effect
  bool named = false;         // first, or confounded with the first or with the calibration
  std::string how;            // "first", "confounded with X", "calibration"
  std::vector<std::string> selected;
  std::map<std::string, double> recovered;  // the effect's fit alone (median over scenarios)
  double max_rel_error = 0;   // largest |θ̂ − θ| / |θ − neutral| (|θ| for a shape parameter)
  double baseline_heldout = 0;  // held-out baseline gap (mean z²)
  double shrink_heldout_pct = 0;
  bool pass = false;
};

// The protocol's cells simulated with params (the article's twelve columns and the others).
std::vector<records::PanelMetrics> SimulateTable(const sim::SimParams& params,
                                                 const SimulateOptions& options);

// Checks one diagnosis against the effect that made its table.
CaseOutcome Judge(const DiagnoseResult& result, const WithheldCase& truth);

// Each case's table simulated at seed truth_seed + its index and diagnosed with `base`, one set
// of simulations serving every case. Throws std::invalid_argument for a case the registry
// refuses or a diagnosis that fails.
std::vector<CaseOutcome> RunWithheldCases(const sim::SimParams& base,
                                          const std::vector<WithheldCase>& cases,
                                          const DiagnoseParams& params, std::uint64_t truth_seed);

// The cases as a Markdown table: effect, size, truth, rank, recovered, shrink, pass.
std::string FormatCases(const std::vector<CaseOutcome>& outcomes);

}  // namespace depthbias::gap
