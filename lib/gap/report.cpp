#include "gap/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "gap/json.h"
#include "gap/report_util.h"
#include "gap/select.h"

namespace depthbias::gap {
namespace {

using text::Num;
using text::GapTableHeader;
using text::GapTableRow;
using text::Pct;
using text::ParamsText;

const Candidate& CandidateOf(const DiagnoseResult& r, const TermFit& t) {
  return r.candidates[t.term.candidate];
}

// "shared", "per light", "per scenario".
std::string ScopeText(Scope scope) {
  std::string s = ScopeName(scope);
  std::replace(s.begin(), s.end(), '_', ' ');
  return s;
}

void GapJsonStat(JsonWriter& w, const std::string& key, const DiagnoseResult& r,
                 const GapStat& g) {
  w.BeginObject(key);
  w.Number("overall", g.overall).Integer("observations", g.count);
  w.BeginObject("per_metric");
  for (size_t k = 0; k < r.metric_names.size() && k < g.mean_sq.size(); ++k)
    w.Number(r.metric_names[k], g.mean_sq[k]);
  w.EndObject().EndObject();
}

// {param: value} or {group: {param: value}} (a light or a scenario); with ci, {param: [lo, hi]}.
void ParamsJson(JsonWriter& w, const std::string& key, const DiagnoseResult& r, const TermFit& t,
                bool ci) {
  const Candidate& c = CandidateOf(r, t);
  auto one = [&](int g) {
    for (size_t a = 0; a < c.axes.size(); ++a) {
      if (!ci) {
        w.Number(c.axes[a].param, t.values[g][a]);
      } else {
        w.BeginArray(c.axes[a].param).Number(t.ci_lo[g][a]).Number(t.ci_hi[g][a]).EndArray();
      }
    }
  };
  w.BeginObject(key);
  if (t.term.scope == Scope::kShared) {
    one(0);
  } else {
    for (size_t g = 0; g < t.values.size(); ++g) {
      w.BeginObject(ScopeGroupName(r.design, t.term.scope, static_cast<int>(g)));
      one(static_cast<int>(g));
      w.EndObject();
    }
  }
  w.EndObject();
}

void CellGapJson(JsonWriter& w, const DiagnoseResult& r, const CellGap& c) {
  w.BeginObject();
  w.String("bag", r.design.bag[c.cell]).Number("chi2", c.chi2).Integer("df", c.df);
  w.Number("p_value", c.p_value).String("worst_metric", r.metric_names[c.worst]);
  w.Number("worst_z", c.worst_z);
  w.EndObject();
}

std::string CellName(const DiagnoseResult& r, int c) {
  const sim::Cell& cell = r.design.cells[c];
  return cell.light + " " + cell.preset + " emitter " + (cell.emitter_on ? "on" : "off") + " " +
         Num(cell.distance_m) + " m " + Num(cell.angle_deg) + "°";
}

void NoiseJson(JsonWriter& w, const DiagnoseResult& r) {
  const PlacementEstimate& pe = r.placement;
  w.BeginObject("noise");
  w.BeginObject("replicate");
  for (size_t k = 0; k < r.metric_names.size(); ++k) {
    w.BeginObject(r.metric_names[k]).Number("at_10m", r.noise.scale[k]);
    w.String("method", r.noise.method[k]).Integer("pairs", r.noise.pairs[k]).EndObject();
  }
  w.EndObject();
  // The simulation's own scatter (noise.h): the base against itself with the panels moved
  // sideways by less than a pixel.
  w.BeginObject("simulation");
  for (size_t k = 0; k < r.noise.simulation.size(); ++k)
    w.BeginObject(r.metric_names[k]).Number("at_10m", r.noise.simulation[k]).EndObject();
  w.EndObject();
  w.BeginObject("placement");
  if (!pe.empty()) {
    w.String("unit", "test point (light, distance, angle)").Integer("test_points", pe.num_points);
    for (size_t k = 0; k < r.metric_names.size(); ++k) {
      const int m = r.design.metrics[k];
      w.BeginObject(r.metric_names[k]);
      w.String("law", m == kMedianBias ? "a + b·D [m]" : "a · (D / 10 m)^e");
      if (m != kMedianBias) w.Number("e", InfoOf(m).placement_exponent);
      w.Number("a", pe.a[k]).Number("b", pe.b[k]).Integer("test_points_used", pe.points_used[k]);
      if (pe.coupling.size() > k && pe.floor_of[k] >= 0)
        w.Number("coupling_to_median", pe.coupling[k]);
      w.BeginArray("at");
      for (double d : {4.0, 8.0, 12.0, 16.0}) {
        w.BeginObject().Number("distance_m", d);
        w.Number("scatter", pe.Law(static_cast<int>(k), m, d));
        if (pe.floor_of.size() > k && pe.floor_of[k] >= 0)
          w.Number("floor", pe.Floor(static_cast<int>(k), d));
        if (m == kMedianBias)
          w.Number("pct_of_distance", 100 * pe.Law(static_cast<int>(k), m, d) / d);
        w.EndObject();
      }
      w.EndArray();
      w.BeginArray("test_points");
      for (int t = 0; t < pe.num_points; ++t) {
        w.BeginObject().String("light", pe.point_light[t]).Bool("flagged", pe.flagged[k][t]);
        w.Number("distance_m", pe.point_distance_m[t]).Number("angle_deg", pe.point_angle_deg[t]);
        w.Number("departure", pe.departure[k][t]).Number("z", pe.departure_z[k][t]);
        if (m == kMedianBias)
          w.String("direction", pe.departure[k][t] > 0 ? "over-reads" : "under-reads");
        w.EndObject();
      }
      w.EndArray().EndObject();
    }
  }
  w.EndObject();
  w.BeginArray("emitter");
  for (const EmitterGap& e : r.noise.emitter) {
    w.BeginObject().String("scenario", r.design.scenario_names[e.scenario]);
    w.Number("distance_m", e.distance_m).String("metric", r.metric_names[e.k]);
    w.Integer("pairs", e.pairs).Number("mismatch", e.mean).Number("se", e.se).Number("z", e.z);
    w.EndObject();
  }
  w.EndArray().EndObject();
}

void NestedJson(JsonWriter& w, const DiagnoseResult& r) {
  const Nested& n = r.nested;
  if (!n.run) {
    w.Null("nested");
    return;
  }
  w.BeginObject("nested");
  w.BeginArray("folds");
  for (const NestedFold& f : n.folds) {
    w.BeginObject().String("held", f.held).Integer("cells", f.cells);
    w.BeginArray("selected");
    for (const auto& s : f.selected) w.String(s);
    w.EndArray();
    w.Number("deviance_calibrated", f.deviance_calibrated);
    w.Number("deviance_selected", f.deviance_selected).Bool("simulated", f.simulated);
    w.Number("simulated_calibrated_sq", f.simulated_calibrated_sq);
    w.Number("simulated_sq", f.simulated_sq);
    w.BeginArray("effect_gain_simulated");
    for (double g : f.effect_gain_simulated) w.Number(g);
    w.EndArray().BeginArray("effect_share_moved");
    for (double g : f.effect_share_moved) w.Number(g);
    w.EndArray().BeginObject("simulated_sq_per_metric");  // {calibrated, selected}: {metric: Σz²}
    for (const auto* v : {&f.simulated_calibrated_sq_metric, &f.simulated_sq_metric}) {
      w.BeginObject(v == &f.simulated_sq_metric ? "selected" : "calibrated");
      for (size_t k = 0; k < v->size() && k < r.metric_names.size(); ++k)
        w.Number(r.metric_names[k], (*v)[k]);
      w.EndObject();
    }
    w.EndObject().BeginObject("calibration").BeginArray("scenarios");  // the fold's own
    for (size_t s = 0; s < f.scenarios_calibrated.size() && s < f.scenarios_selected.size(); ++s)
      w.BeginObject().String("scenario", r.design.scenario_names[s]).BeginObject("sigma_d_px")
          .Number("calibrated", f.scenarios_calibrated[s].sigma_d_px)
          .Number("selected", f.scenarios_selected[s].sigma_d_px).EndObject()
          .BeginObject("invalid_prob").Number("calibrated", f.scenarios_calibrated[s].invalid_prob)
          .Number("selected", f.scenarios_selected[s].invalid_prob).EndObject().EndObject();
    w.EndArray().EndObject().BeginObject("params");  // the selection's values, effect by effect
    for (const TermFit& t : f.fit.terms) ParamsJson(w, CandidateOf(r, t).effect, r, t, false);
    w.EndObject().EndObject();
  }
  w.EndArray();
  GapJsonStat(w, "baseline", r, n.baseline);
  GapJsonStat(w, "calibrated", r, n.calibrated);
  GapJsonStat(w, "selected", r, n.selected);
  if (n.simulated.count > 0) {  // every fold simulated
    GapJsonStat(w, "simulated", r, n.simulated);
    GapJsonStat(w, "simulated_calibrated", r, n.simulated_calibrated);
  } else {
    w.Null("simulated").Null("simulated_calibrated");
  }
  w.Number("gain", n.gain).Number("gain_simulated", n.gain_simulated);
  w.Number("share_moved", n.share_moved);
  // The folds' selections restricted as the keep rule read them last (null: none left out).
  if (n.kept.empty()) {
    w.Null("restricted").EndObject();
    return;
  }
  w.BeginObject("restricted").BeginArray("effects");
  for (const std::string& e : n.kept) w.String(e);
  GapJsonStat(w.EndArray(), "simulated", r, n.simulated_kept);
  w.Number("gain_simulated", n.gain_simulated_kept).Number("share_moved", n.share_moved_kept);
  w.EndObject().EndObject();
}

void OpenWorldJson(JsonWriter& w, const DiagnoseResult& r) {
  w.BeginArray("ambiguous");
  for (const Ambiguity& a : r.ambiguous) {
    w.BeginObject().BeginArray("one_of");
    for (const auto& e : a.effects) w.String(e);
    w.EndArray().BeginArray("sizes");
    for (const auto& s : a.sizes) w.String(s);
    w.EndArray().Number("correlation", a.correlation);
    if (!a.selection_with.empty()) w.BeginObject("selection_with");  // effects[0] the cause
    for (const TermFit& t : a.selection_with) ParamsJson(w, CandidateOf(r, t).effect, r, t, false);
    if (!a.selection_with.empty())  // rounds against their joint simulation; 0: not simulated
      w.EndObject().Number("selection_with_rounds", a.selection_with_rounds);
    (a.why.empty() ? w : w.String("why", a.why)).EndObject();
  }
  w.EndArray().BeginArray("not_kept");
  for (const auto& d : r.dropped) w.String(d);
  w.EndArray();
  w.BeginArray("unexplained");
  for (const Unexplained& u : r.unexplained) {
    w.BeginObject().String("metric", u.metric).String("where", u.where);
    w.Number("size", u.size).Number("size_se", u.size_se).String("unit", u.unit);
    w.String("form", u.form).Number("size_at_far_end", u.size_at_max);
    w.Number("share_pct", u.share_pct).Number("chi2", u.chi2).Integer("cells", u.df);
    w.Number("p_value", u.p_value).Bool("beyond_placement_law", u.beyond_placement_law);
    w.BeginArray("bags");
    for (int c : u.cells) w.String(r.design.bag[c]);
    w.EndArray().EndObject();
  }
  w.EndArray();
  LimitsJson(w, r.limits);
}

}  // namespace

std::string GapJson(const DiagnoseResult& r, const DiagnoseParams& p, const ReportContext& ctx) {
  JsonWriter w;
  w.BeginObject();
  w.String("tool", "diagnose_gap").String("version", ctx.version);
  w.BeginObject("input");
  w.String("file", ctx.input).String("sha256", ctx.input_sha256);
  w.Integer("rows_used", r.design.num_cells());
  w.BeginArray("rows_skipped");
  for (const auto& s : r.design.skipped) w.String(s);
  w.EndArray().EndObject();
  w.BeginObject("settings");
  w.String("protocol", ctx.protocol).String("sensor", ctx.sensor);
  w.Integer("seed", static_cast<long long>(ctx.seed)).Integer("frames", p.simulate.frames);
  w.String("holdout", r.holdout).Integer("folds", r.folds);
  w.Number("huber_k", p.fit.huber_k).Number("tau_log_sigma", p.fit.tau_log_sigma);
  w.Number("tau_logit_p", p.fit.tau_logit_p).Bool("joint_window", p.fit.joint_window);
  w.Number("confounded_r", p.confounded_r).Number("absorb_r", p.absorb_r).Number("alpha", p.alpha);
  w.Number("min_effect_shrink_pct", p.min_effect_shrink_pct);
  w.Number("min_own_shrink_pct", p.min_own_shrink_pct);
  w.Number("min_moved_shrink_pct", p.min_moved_shrink_pct);
  w.Number("min_own_moved_shrink_pct", p.min_own_moved_shrink_pct);
  w.Integer("simulations", r.simulations);
  w.BeginArray("candidates");
  for (const auto& c : r.candidates) w.String(c.effect);
  w.EndArray().EndObject();

  w.BeginArray("metrics");
  for (size_t k = 0; k < r.metric_names.size(); ++k) {
    const MetricInfo& info = InfoOf(r.design.metrics[k]);
    w.BeginObject().String("name", info.name).String("unit", info.unit);
    w.String("meaning", info.meaning).Number("noise_at_10m", r.noise.scale[k]);
    w.Number("noise_exponent", info.noise_exponent);
    w.Number("placement_exponent", info.placement_exponent);
    w.String("noise_method", r.noise.method[k]);
    w.Integer("noise_pairs", r.noise.pairs[k]).Number("dispersion", r.dispersion[k]);
    w.Number("dispersion_placement", r.dispersion[r.metric_names.size() + k]).EndObject();
  }
  w.EndArray();

  NoiseJson(w, r);
  w.BeginObject("baseline_gap");
  GapJsonStat(w, "in_sample", r, r.baseline);
  GapJsonStat(w, "heldout_cells", r, r.baseline_heldout);
  w.EndObject();

  const Localization& loc = r.localization;
  w.BeginObject("localization");
  w.BeginObject("share_pct");
  for (size_t t = 0; t < loc.terms.size(); ++t) w.Number(loc.terms[t], loc.overall_pct[t]);
  w.EndObject();
  w.BeginObject("share_pct_per_metric");
  for (size_t k = 0; k < loc.metric_pct.size(); ++k) {
    w.BeginObject(r.metric_names[k]);
    for (size_t t = 0; t < loc.terms.size(); ++t) w.Number(loc.terms[t], loc.metric_pct[k][t]);
    w.EndObject();
  }
  w.EndObject();
  w.BeginObject("metric_share_pct");
  for (size_t k = 0; k < loc.metric_share_pct.size(); ++k)
    w.Number(r.metric_names[k], loc.metric_share_pct[k]);
  w.EndObject();
  w.BeginArray("significant_cells");
  for (const auto& c : loc.significant) CellGapJson(w, r, c);
  w.EndArray().EndObject();

  w.BeginObject("calibration");
  w.BeginArray("scenarios");
  for (size_t s = 0; s < r.calibrated.size(); ++s) {
    w.BeginObject().String("scenario", r.design.scenario_names[s]);
    w.BeginObject("sigma_d_px").Number("configured", r.configured[s].sigma_d_px);
    w.Number("fitted", r.calibrated[s].sigma_d_px).EndObject();
    w.BeginObject("invalid_prob").Number("configured", r.configured[s].invalid_prob);
    w.Number("fitted", r.calibrated[s].invalid_prob).EndObject();
    w.EndObject();
  }
  w.EndArray();
  GapJsonStat(w, "gap_in_sample", r, r.calibration_in);
  GapJsonStat(w, "gap_heldout", r, r.calibration_heldout);
  w.EndObject();

  w.BeginArray("effects");
  for (size_t i = 0; i < r.effects.size(); ++i) {
    const EffectResult& e = r.effects[i];
    const sim::EffectInfo* info = sim::FindEffect(e.name);
    w.BeginObject().String("name", e.name).Integer("rank", static_cast<long long>(i + 1));
    w.String("scope", ScopeName(e.fit.term.scope));
    ParamsJson(w, "params", r, e.fit, false);
    ParamsJson(w, "ci95", r, e.fit, true);
    w.Number("delta_bic", e.delta_bic).Number("delta_bic_shared", e.delta_bic_shared);
    w.Number("delta_bic_per_light", e.delta_bic_per_light);
    w.Number("delta_bic_per_scenario", e.delta_bic_per_scenario);
    w.Number("heldout_gain", e.heldout_gain).Bool("earns", e.earns);
    w.Number("shrink_in_sample_pct", e.shrink_in_sample_pct);
    w.Number("shrink_heldout_pct", e.shrink_heldout_pct);
    GapJsonStat(w, "gap_in_sample", r, e.in_sample);
    GapJsonStat(w, "gap_heldout", r, e.heldout);
    if (info) w.String("cause", info->cause).String("signature", info->signature);
    w.EndObject();
  }
  w.EndArray();

  w.BeginArray("selected");
  for (size_t i = 0; i < r.selected.terms.size(); ++i) {
    const TermFit& t = r.selected.terms[i];
    w.BeginObject().String("name", CandidateOf(r, t).effect);
    ParamsJson(w.String("scope", ScopeName(t.term.scope)), "params", r, t, false);
    ParamsJson(w, "ci95", r, t, true);
    SpreadsEvidenceJson(w, r.spreads, t.term.candidate);
    if (i < r.steps.size())
      w.Number("delta_bic", r.steps[i].delta_bic).Number("heldout_gain", r.steps[i].heldout_gain);
    if (i < r.size_spread.size()) {
      // Shared: the spread itself; per light or scenario: one such object per group checked.
      const std::vector<SizeSpread>& spread = r.size_spread[i];
      auto one = [&](const char* key, const SizeSpread& sp) {
        w.BeginObject(key).BeginArray("values");
        for (double v : sp.folds) w.Number(v);
        w.EndArray().Number("jackknife_se", sp.se_folds).Number("t", sp.t);
        w.BeginArray("ci95_fit").Number(sp.fit_lo).Number(sp.fit_hi).EndArray();
        w.Bool("widened", sp.widened).EndObject();
      };
      if (t.term.scope == Scope::kShared) {
        if (!spread.empty() && spread[0].checked) one("over_folds", spread[0]);
      } else if (std::any_of(spread.begin(), spread.end(),
                             [](const SizeSpread& g) { return g.checked; })) {
        w.BeginObject("over_folds");
        for (size_t g = 0; g < spread.size(); ++g)
          if (spread[g].checked)
            one(ScopeGroupName(r.design, t.term.scope, static_cast<int>(g)).c_str(), spread[g]);
        w.EndObject();
      }
    }
    w.EndObject();
  }
  w.EndArray();

  w.BeginArray("confounded");
  for (const auto& c : r.confounded) {
    w.BeginObject().BeginArray("effects").String(c.a).String(c.b).EndArray();
    w.Number("correlation", c.correlation).EndObject();
  }
  w.EndArray();
  w.BeginArray("signature_correlations");
  for (const auto& c : r.correlations) {
    w.BeginObject().BeginArray("effects").String(c.a).String(c.b).EndArray();
    w.Number("correlation", c.correlation).EndObject();
  }
  w.EndArray();

  w.BeginObject("how_far");
  GapJsonStat(w, "baseline", r, r.baseline);
  GapJsonStat(w, "calibrated", r, r.calibration_in);
  GapJsonStat(w, "selected_in_sample", r, r.selected_in);
  GapJsonStat(w, "selected_heldout", r, r.selected_heldout);
  if (r.verified) GapJsonStat(w, "selected_simulated", r, r.verified_in);
  else w.Null("selected_simulated");
  w.Number("shrink_in_sample_pct", Shrink(r.baseline, r.selected_in));
  w.Number("shrink_heldout_pct", Shrink(r.baseline_heldout, r.selected_heldout));
  w.Number("shrink_heldout_nested_pct", r.nested.shrink_heldout_nested_pct);
  w.Number("shrink_simulated_pct", r.nested.shrink_simulated_pct);
  NestedJson(w, r);
  w.EndObject();
  OpenWorldJson(w, r);

  w.BeginObject("remaining_gap");
  GapJsonStat(w, "in_sample", r, r.selected_in);
  GapJsonStat(w, "heldout", r, r.selected_heldout);
  w.BeginArray("cells");
  for (const auto& c : r.remaining) CellGapJson(w, r, c);
  w.EndArray().EndObject();

  const int kk = static_cast<int>(r.metric_names.size());
  std::vector<char> sig_base(r.design.num_cells(), 0), sig_left(r.design.num_cells(), 0);
  for (const auto& c : r.localization.significant) sig_base[c.cell] = 1;
  for (const auto& c : r.remaining) sig_left[c.cell] = 1;
  w.BeginArray("cells");
  for (int c = 0; c < r.design.num_cells(); ++c) {
    const sim::Cell& cell = r.design.cells[c];
    w.BeginObject().String("bag", r.design.bag[c]).String("light", cell.light);
    w.String("preset", cell.preset).String("emitter", cell.emitter_on ? "on" : "off");
    w.Number("distance_m", cell.distance_m).Number("angle_deg", cell.angle_deg);
    auto row = [&](const std::string& key, const std::vector<double>& v) {
      w.BeginObject(key);
      for (int k = 0; k < kk; ++k)
        w.Number(r.metric_names[k], v.empty() ? NAN : v[static_cast<size_t>(c) * kk + k]);
      w.EndObject();
    };
    for (const auto& [key, v] : {std::make_pair("real", &r.design.real),
                                 {"sim", &r.sim_base}, {"z_baseline", &r.z_base},
                                 {"z_selected", &r.z_selected},
                                 {"z_heldout", &r.z_selected_heldout}})
      row(key, *v);
    if (r.nested.run) {  // the outer fold holding the cell out: its z and their unit
      w.BeginObject("nested");
      for (const auto& [key, v] : {std::make_pair("unit", &r.nested.unit),
                                   {"z_baseline", &r.nested.z_baseline},
                                   {"z_simulated", &r.nested.z_simulated}})
        row(key, *v);
      w.EndObject();
    }
    w.Bool("significant_baseline", sig_base[c]).Bool("significant_after", sig_left[c]);
    w.EndObject();
  }
  w.EndArray();
  w.EndObject();
  return w.Text();
}

std::string GapSummary(const DiagnoseResult& r) { return text::Headline(r); }

std::string GapMarkdown(const DiagnoseResult& r, const DiagnoseParams& p,
                        const ReportContext& ctx) {
  std::ostringstream o;
  const Localization& loc = r.localization;
  const int kk = static_cast<int>(r.metric_names.size());
  o << "# Sim-to-real gap: " << ctx.input << "\n\n"
    << "`diagnose_gap` " << ctx.version << ": " << r.design.num_cells() << " rows of `"
    << ctx.input << "` (sha256 " << ctx.input_sha256.substr(0, 16) << "…) against the simulator ("
    << ctx.protocol << ", sensor " << ctx.sensor << ", seed " << ctx.seed << ", "
    << p.simulate.frames << " frames a cell, " << r.simulations << " simulations of the table), "
    << "held out by " << r.holdout << " (" << r.folds << " folds).\n\n";
  if (!r.design.skipped.empty())
    o << "Rows left out: " << r.design.skipped.size() << " (" << r.design.skipped.front()
      << (r.design.skipped.size() > 1 ? ", …" : "") << ").\n\n";

  o << "## In short\n\n```\n" << GapSummary(r) << "```\n\n" << text::EvidenceMarkdown(r, p);

  o << "## 1. The gap\n\n"
    << "Per recording and metric, z = (real − simulated) / noise. The noise of each metric is "
    << "measured, not assumed; how is said per metric. The gap is the mean of z² over the "
    << "table: 1 means the simulator is as close to the camera as the camera is to itself. About "
    << "the widest model (every continuous candidate effect fitted together), the dispersion φ is "
    << "how much wider than the replicate noise a test point's recordings spread about their "
    << "mean, ψ how much wider than the placement law the test points' means spread.\n\n"
    << "| metric | unit | noise at 10 m | noise ∝ (Z/10 m)^ | measured from | φ | ψ | baseline "
       "gap | held-out cells |\n|---|---|---|---|---|---|---|---|---|\n";
  for (int k = 0; k < kk; ++k) {
    const MetricInfo& info = InfoOf(r.design.metrics[k]);
    o << "| " << info.name << " | " << info.unit << " | " << Num(r.noise.scale[k]) << " | "
      << Num(info.noise_exponent) << " | " << r.noise.method[k] << " (" << r.noise.pairs[k]
      << ") | " << Num(r.dispersion[k]) << " | " << Num(r.dispersion[kk + k]) << " | "
      << Num(r.baseline.mean_sq[k]) << " | " << Num(r.baseline_heldout.mean_sq[k]) << " |\n";
  }
  o << "\nReplicates are the emitter on and off rows of one test point: the same panel "
    << "placement recorded twice, so the difference of their residuals is noise whatever the "
    << "gap is (robust scale, 1.4826 · median |Δ| / √2). Quantized metrics (median, mean − "
    << "median, spreads of depths, panel width) also carry their quantization step in quadrature: "
    << "two recordings of one panel mostly read the same quantized median.\n\n";

  o << "## 2. Where\n\nShare of Σz² by factor (sequential sums of squares on indicator "
    << "columns: exact for a balanced design; \"rest\" holds higher-order interactions and "
    << "replicate noise).\n\n| term | all metrics |";
  for (int k = 0; k < kk; ++k) o << " " << r.metric_names[k] << " |";
  o << "\n|---|---|";
  for (int k = 0; k < kk; ++k) o << "---|";
  o << "\n";
  for (size_t t = 0; t < loc.terms.size(); ++t) {
    o << "| " << loc.terms[t] << " | " << Pct(loc.overall_pct[t]) << " |";
    for (int k = 0; k < kk; ++k) o << " " << Pct(loc.metric_pct[k][t]) << " |";
    o << "\n";
  }
  o << "| share of Σz² | 100 % |";
  for (int k = 0; k < kk; ++k) o << " " << Pct(loc.metric_share_pct[k]) << " |";
  o << "\n\n" << loc.significant.size() << " of " << r.design.num_cells()
    << " recordings depart significantly (χ² over their metrics, p < " << Num(p.alpha)
    << " / " << r.design.num_cells() << "). The largest:\n\n"
    << "| recording | χ² | worst metric | its z |\n|---|---|---|---|\n";
  for (size_t i = 0; i < loc.significant.size() && i < 12; ++i) {
    const CellGap& c = loc.significant[i];
    o << "| " << CellName(r, c.cell) << " | " << Num(c.chi2) << " | "
      << r.metric_names[c.worst] << " | " << Num(c.worst_z) << " |\n";
  }

  o << "\n## 3. Which effect\n\n"
    << "The reference is the calibrated base: the configured sensor with each scenario's σ_d "
    << "and hole probability free to move within their prior widths (log σ_d ± "
    << Num(p.fit.tau_log_sigma) << ", logit p ± " << Num(p.fit.tau_logit_p) << "):\n\n"
    << "| scenario | σ_d configured → fitted [px] | hole probability configured → fitted |\n"
    << "|---|---|---|\n";
  for (size_t s = 0; s < r.calibrated.size(); ++s)
    o << "| " << r.design.scenario_names[s] << " | " << Num(r.configured[s].sigma_d_px, 4)
      << " → " << Num(r.calibrated[s].sigma_d_px, 4) << " | "
      << Num(r.configured[s].invalid_prob) << " → " << Num(r.calibrated[s].invalid_prob)
      << " |\n";
  o << "\nEvery candidate alone with it, parameters shared, per light or per scenario (the best "
    << "by BIC, kept where it also beats the shared fit held out by one standard error), "
    << "ranked by held-out gain (the reference's held-out deviance minus the effect's; "
    << "ΔBIC = D(reference) − D(effect) − k·ln n). An effect earns its place with both above 0. "
    << "Shrink: of the baseline gap, in sample and on held-out cells.\n\n"
    << "| rank | effect | scope | parameters [95 % interval] | ΔBIC | held-out gain | shrink in "
       "sample | shrink held out | earns |\n|---|---|---|---|---|---|---|---|---|\n";
  for (size_t i = 0; i < r.effects.size(); ++i) {
    const EffectResult& e = r.effects[i];
    o << "| " << i + 1 << " | " << e.name << " | " << ScopeText(e.scope)
      << " | " << ParamsText(r, e.fit, true) << " | " << Num(e.delta_bic) << " | "
      << Num(e.heldout_gain) << " | " << Pct(e.shrink_in_sample_pct) << " | "
      << Pct(e.shrink_heldout_pct) << " | " << (e.earns ? "yes" : "no") << " |\n";
  }
  o << "\nForward selection (the effect of largest held-out gain among those earning both, "
    << "refitted jointly with those already in):\n\n";
  if (r.steps.empty()) o << "- nothing earns its place: no registered effect is named.\n";
  for (size_t i = 0; i < r.steps.size(); ++i)
    o << "- " << i + 1 << ". " << r.steps[i].effect << " ("
      << ScopeText(r.steps[i].scope) << "): ΔBIC "
      << Num(r.steps[i].delta_bic) << ", held-out gain " << Num(r.steps[i].heldout_gain) << "\n";
  if (!r.selected.terms.empty()) {
    o << "\nSelected, fitted together" << text::WidthIntervalNote(r)
      << ":\n\n| effect | parameters [95 % interval] |\n|---|---|\n";
    for (const TermFit& t : r.selected.terms)
      o << "| " << CandidateOf(r, t).effect << " | " << ParamsText(r, t, true) << " |\n";
  }
  o << "\nConfounded (signatures with |r| ≥ " << Num(p.confounded_r)
    << " on this design, or an effect along one calibration direction with r ≥ "
    << Num(p.absorb_r) << "): these cannot be told apart here, and none is picked over "
    << "the other.\n\n";
  if (r.confounded.empty()) o << "- none\n";
  for (const auto& c : r.confounded)
    o << "- " << c.a << " ~ " << c.b << ": r = " << Num(c.correlation) << "\n";
  std::vector<Confounded> strong;
  for (const auto& c : r.correlations)
    if (std::fabs(c.correlation) >= 0.7 && std::fabs(c.correlation) < p.confounded_r)
      strong.push_back(c);
  if (!strong.empty()) {
    o << "\nStrongly correlated but told apart (0.7 ≤ |r| < " << Num(p.confounded_r) << "):";
    for (const auto& c : strong)
      o << " " << c.a << " ~ " << c.b << " " << Num(c.correlation) << ";";
    o << "\n";
  }

  o << "\n## 4. How far\n\n" << GapTableHeader("gap", r.metric_names);
  auto row = [&](const std::string& name, const GapStat& g) {
    o << GapTableRow(name, g, r.metric_names.size());
  };
  row("baseline (configured sensor)", r.baseline);
  row("calibrated base", r.calibration_in);
  row("selected, in sample", r.selected_in);
  row("baseline, held-out cells", r.baseline_heldout);
  row("calibrated base, held out", r.calibration_heldout);
  row("selected, held out", r.selected_heldout);
  if (r.verified) row("selected, simulated at the fit", r.verified_in);
  o << "\nShrink of the gap: " << Pct(Shrink(r.baseline, r.selected_in)) << " in sample, "
    << Pct(Shrink(r.baseline_heldout, r.selected_heldout)) << " on held-out cells"
    << (r.verified ? "; the selected effects simulated at their fitted values leave " +
                         Num(r.verified_in.overall) + " (the fits add effects' departures; the "
                         "simulation composes them)."
                   : ".")
    << "\n\n## 5. What is left\n\n";
  if (r.remaining.empty()) {
    o << "No recording departs significantly once the selected effects are added.\n";
  } else {
    o << r.remaining.size() << " of " << r.design.num_cells()
      << " recordings still depart significantly. The largest:\n\n"
      << "| recording | χ² | worst metric | its z |\n|---|---|---|---|\n";
    for (size_t i = 0; i < r.remaining.size() && i < 15; ++i) {
      const CellGap& c = r.remaining[i];
      o << "| " << CellName(r, c.cell) << " | " << Num(c.chi2) << " | "
        << r.metric_names[c.worst] << " | " << Num(c.worst_z) << " |\n";
    }
  }
  return o.str();
}

}  // namespace depthbias::gap
