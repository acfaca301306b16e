#include "gap/cases.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>

namespace depthbias::gap {
namespace {

std::string Num(double v, int digits = 3) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

std::string Params(const std::map<std::string, double>& p) {
  std::string s;
  for (const auto& [k, v] : p) s += (s.empty() ? "" : ", ") + k + " " + Num(v);
  return s;
}

}  // namespace

std::vector<WithheldCase> DefaultWithheldCases() {
  // Small: a few noise units of the most affected metric on the far cells; large: the effect
  // dominating the table.
  return {
      {"disparity_offset", "small", {{"delta_px", 0.07}}},
      {"disparity_offset", "large", {{"delta_px", 0.35}}},
      {"depth_scale", "small", {{"scale_rel", 0.01}}},
      {"depth_scale", "large", {{"scale_rel", 0.06}}},
      {"range_vs_depth", "small", {{"weight", 0.3}}},
      {"range_vs_depth", "large", {{"weight", 0.85}}},
      {"radial_disparity_residual", "small", {{"k_px", 0.2}}},
      {"radial_disparity_residual", "large", {{"k_px", 0.8}}},
      {"disparity_noise_gain", "small", {{"gain", 1.3}}},
      {"disparity_noise_gain", "large", {{"gain", 2.0}}},
      {"invalidation_gain", "small", {{"gain", 1.8}}},
      {"invalidation_gain", "large", {{"gain", 5.0}}},
      {"panel_tilt", "small", {{"yaw_deg", 10}}},
      {"panel_tilt", "large", {{"yaw_deg", 30}}},
      {"temporal_drift", "small", {{"rate_px_per_s", 0.4}}},
      {"temporal_drift", "large", {{"rate_px_per_s", 0.8}}},
      {"edge_mixing", "small", {{"width_px", 3}, {"strength", 0.5}}},
      {"edge_mixing", "large", {{"width_px", 5}, {"strength", 0.9}}},
      {"region_spill", "small", {{"width_px", 2}, {"background_rel", 2.0}}},
      {"region_spill", "large", {{"width_px", 4}, {"background_rel", 2.5}}},
  };
}

std::vector<records::PanelMetrics> SimulateTable(const sim::SimParams& params,
                                                 const SimulateOptions& options) {
  sim::MetricsParams mp;
  mp.frames = options.frames;
  mp.threads = options.threads;
  mp.region_margin_px = options.region_margin_px;
  std::vector<records::PanelMetrics> rows;
  for (const auto& r : sim::SimulateProtocolMetrics(params, mp)) rows.push_back(r.metrics);
  return rows;
}

CaseOutcome Judge(const DiagnoseResult& r, const WithheldCase& truth) {
  CaseOutcome o;
  o.truth = truth;
  for (const auto& s : r.steps) o.selected.push_back(s.effect);
  if (!r.effects.empty()) o.top = r.effects.front().name;
  for (size_t i = 0; i < r.effects.size(); ++i)
    if (r.effects[i].name == truth.effect) o.rank = static_cast<int>(i) + 1;
  if (o.rank == 1) {
    o.named = true, o.how = "first";
  } else if (r.ConfoundedWith(truth.effect, o.top)) {
    o.named = true, o.how = "confounded with " + o.top;
  } else if (r.ConfoundedWith(truth.effect, "calibration:sigma_d") ||
             r.ConfoundedWith(truth.effect, "calibration:hole_prob")) {
    o.named = true, o.how = "confounded with the calibration";
  }
  const EffectResult* e = r.Effect(truth.effect);
  if (!e) return o;
  const sim::EffectInfo* info = sim::FindEffect(truth.effect);
  const Candidate* cand = nullptr;
  const std::vector<Candidate> all = DefaultCandidates();
  for (const Candidate& c : all)
    if (c.effect == truth.effect) cand = &c;
  for (size_t a = 0; a < info->params.size(); ++a) {
    const std::string& name = info->params[a].name;
    std::vector<double> v;
    for (size_t g = 0; g < e->fit.values.size(); ++g)
      if (e->fit.group_used[g]) v.push_back(e->fit.values[g][a]);
    std::sort(v.begin(), v.end());
    const size_t mid = v.size() / 2;
    const double got = v.empty()      ? NAN
                       : v.size() % 2 ? v[mid]
                                      : 0.5 * (v[mid - 1] + v[mid]);
    o.recovered[name] = got;
    const double want = truth.params.count(name) ? truth.params.at(name)
                                                 : info->params[a].default_value;
    const double neutral = cand && std::isfinite(cand->axes[a].neutral) ? cand->axes[a].neutral : 0;
    const double scale = std::fabs(want - neutral) > 0 ? std::fabs(want - neutral) : 1.0;
    o.max_rel_error = std::max(o.max_rel_error, std::fabs(got - want) / scale);
    if (!std::isfinite(got)) o.max_rel_error = INFINITY;
  }
  o.baseline_heldout = r.baseline_heldout.overall;
  o.shrink_heldout_pct = e->shrink_heldout_pct;
  o.pass = o.named && o.max_rel_error <= 0.2 && o.shrink_heldout_pct >= 70;
  return o;
}

std::vector<CaseOutcome> RunWithheldCases(const sim::SimParams& base,
                                          const std::vector<WithheldCase>& cases,
                                          const DiagnoseParams& params, std::uint64_t truth_seed) {
  std::vector<CaseOutcome> out;
  std::unique_ptr<Simulations> sims;
  std::vector<Candidate> candidates;
  std::string why;
  if (!SelectCandidates(params.candidates, &candidates, &why)) throw std::invalid_argument(why);
  for (size_t i = 0; i < cases.size(); ++i) {
    sim::SimParams truth = base;
    truth.seed = truth_seed + i;
    if (!sim::BuildDepartures({{cases[i].effect, cases[i].params}}, &truth.departures, &why))
      throw std::invalid_argument(cases[i].effect + ": " + why);
    Design design;
    if (!BuildDesign(SimulateTable(truth, params.simulate), &design, &why))
      throw std::invalid_argument(cases[i].effect + ": " + why);
    if (!sims || !sims->Matches(design))
      sims = std::make_unique<Simulations>(
          SimulateDesign(base, design, candidates, params.simulate));
    const DiagnoseResult r = DiagnoseWith(design, *sims, base, params);
    if (!r.success) throw std::invalid_argument(cases[i].effect + ": " + r.message);
    out.push_back(Judge(r, cases[i]));
  }
  return out;
}

std::string FormatCases(const std::vector<CaseOutcome>& outcomes) {
  std::string s =
      "| effect | size | truth | rank | named | recovered | max error | held-out gap before | "
      "held-out shrink | selected | pass |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& o : outcomes) {
    std::string sel;
    for (const auto& e : o.selected) sel += (sel.empty() ? "" : ", ") + e;
    s += "| " + o.truth.effect + " | " + o.truth.size + " | " + Params(o.truth.params) + " | " +
         std::to_string(o.rank) + " | " + (o.named ? o.how : "no") + " | " +
         Params(o.recovered) + " | " + Num(100 * o.max_rel_error, 2) + " % | " +
         Num(o.baseline_heldout, 3) + " | " + Num(o.shrink_heldout_pct, 3) + " % | " +
         (sel.empty() ? "none" : sel) + " | " + (o.pass ? "yes" : "**no**") + " |\n";
  }
  return s;
}

}  // namespace depthbias::gap
