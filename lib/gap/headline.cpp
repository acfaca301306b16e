// The report's headline for a safety engineer and the evidence behind it: range error in metres
// and its direction first, then placement, emitter, selection, the open world and the nested
// hold-out (report_util.h).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "gap/noise.h"
#include "gap/report_util.h"
#include "gap/select.h"
#include "gap/unexplained.h"

namespace depthbias::gap::text {
namespace {

// Index of the median bias among the compared metrics (−1: none).
int MedianIndex(const DiagnoseResult& r) {
  for (size_t k = 0; k < r.design.metrics.size(); ++k)
    if (r.design.metrics[k] == kMedianBias) return static_cast<int>(k);
  return -1;
}

// Why two effects are named "one of": their signatures' correlation, or (NaN) the first no
// longer earning its parameters beside the second.
std::string Why(const Ambiguity& a) {
  if (!a.why.empty()) return a.why;
  if (std::isfinite(a.correlation)) return "r = " + Num(a.correlation);
  return "by BIC, " + a.effects[0] + " no longer earns beside " + a.effects.back();
}

// What the selection and the effect named with the calibration read together were that effect
// the cause (Ambiguity::selection_with): "; were it temporal_drift, the selection beside it
// would read disparity_offset …, temporal_drift …", or "".
std::string WithText(const DiagnoseResult& r, const Ambiguity& a) {
  std::string s;
  for (const TermFit& t : a.selection_with) {
    const Candidate& c = r.candidates[t.term.candidate];
    s += s.empty() ? "; were it " + a.effects[0] + ", the selection beside it would read " : ", ";
    s += c.effect + " " + SizeText(c, t);
  }
  if (!s.empty() && a.selection_with_rounds == 0)
    s += " (their departures added: their joint simulation failed)";
  return s;
}

std::string Direction(double metres) {
  return metres > 0 ? "reads farther than the simulator: over-reads (the dangerous direction)"
                    : "reads nearer than the simulator: under-reads";
}

// The median's gap in metres at the far distance before any effect, as the headline's opening
// ("at 16 m the camera … by 0.91 m (95 % ± 0.19 m over 4 test points); "): each test point's
// mean of real − base over its recordings, then their mean and its interval (Student's t: a
// far distance holds a few test points). Empty without test points there.
std::string FarGap(const DiagnoseResult& r, int km) {
  const PlacementEstimate& pe = r.placement;
  if (pe.empty()) return "";
  const int kk = r.design.num_metrics();
  double far = 0;
  for (const sim::Cell& c : r.design.cells) far = std::max(far, c.distance_m);
  std::vector<double> sum(pe.num_points, 0.0), count(pe.num_points, 0.0);
  for (int c = 0; c < r.design.num_cells(); ++c) {
    const size_t at = static_cast<size_t>(c) * kk + km;
    const int t = pe.point[c];
    if (r.design.cells[c].distance_m != far || at >= r.sim_base.size() || t < 0) continue;
    const double d = r.design.real[at] - r.sim_base[at];
    if (std::isfinite(d)) sum[t] += d, count[t] += 1;
  }
  std::vector<double> means;
  for (int t = 0; t < pe.num_points; ++t)
    if (count[t] > 0) means.push_back(sum[t] / count[t]);
  if (means.empty()) return "";
  const double n = static_cast<double>(means.size());
  double mean = 0, ss = 0;
  for (double m : means) mean += m / n;
  for (double m : means) ss += (m - mean) * (m - mean);
  std::ostringstream o;
  o << "at " << Num(far) << " m the camera " << Direction(mean) << " by "
    << Num(std::fabs(mean), 2) << " m";
  if (means.size() >= 2)
    o << " (95 % ± "
      << Num(StudentT975(static_cast<int>(n) - 1) * std::sqrt(ss / (n - 1) / n), 2) << " m over "
      << means.size() << " test points)";
  return o.str() + "; ";
}

const double kEmitterZ = 3.5;  // an emitter mismatch worth a headline (|z|, about p < 0.05/64)

// The range laws' sizes that could go unseen, over-reads first: "over-reads at 16 m up to
// 1.1 m (disparity_offset -0.285 px), …; under-reads …". Empty without a median bias.
std::string Unseen(const DiagnoseResult& r) {
  const DetectionLimits& l = r.limits;
  std::string side_text[2];
  for (int over = 1; over >= 0; --over) {
    std::vector<std::pair<double, std::string>> items;
    for (size_t i = 0; i < l.effects.size() && i < r.candidates.size(); ++i) {
      const DetectionLimit& e = l.effects[i];
      if (!r.candidates[i].range_law) continue;
      for (int side = 0; side < 2; ++side) {
        const double m = e.far_m[side];
        if (!std::isfinite(m) || (m > 0) != (over == 1) || std::fabs(m) < 0.005) continue;
        const bool beyond = !std::isfinite(e.size[side]);
        const Axis& axis = r.candidates[i].axes[0].param == e.param ? r.candidates[i].axes[0]
                                                                    : r.candidates[i].axes.back();
        const double size = beyond ? (side == 0 ? axis.nodes.front() : axis.nodes.back())
                                   : e.size[side];
        const bool bound = size == axis.min_value || size == axis.max_value;
        const std::string more = !beyond ? "" : bound ? ", its bound" : ", the largest simulated";
        items.push_back({std::fabs(m), Num(std::fabs(m), 2) + " m" +
                                           (beyond && !bound ? " and more" : "") + " (" +
                                           e.effect + " " + e.param + " " + Signed(size) + more +
                                           ")"});
      }
    }
    std::sort(items.begin(), items.end(), [](const auto& a, const auto& b) {
      return a.first > b.first;
    });
    for (size_t i = 0; i < items.size(); ++i)
      side_text[over] += (i ? ", " : "") + items[i].second;
  }
  if (side_text[0].empty() && side_text[1].empty()) return "";
  std::string s = "could go unseen: at " + Num(l.far_distance_m) + " m";
  if (!side_text[1].empty()) s += ", over-reads up to " + side_text[1];
  if (!side_text[0].empty()) s += (side_text[1].empty() ? ", " : "; ") +
                                  std::string("under-reads up to ") + side_text[0];
  return s + ": no smaller law would be kept on this table (the fit's test and the share of "
             "the gap an effect must remove; a lower bound)\n";
}

// Every effect's detection limits (limits.h) as a table.
std::string LimitsMarkdown(const DiagnoseResult& r) {
  const DetectionLimits& l = r.limits;
  if (l.effects.empty()) return "";
  std::ostringstream o;
  o << "## What this table cannot see\n\n"
    << "The smallest size of each effect, either way from its absence, that the diagnosis would "
       "keep on this table: the higher of two bars. The fit's test (ΔBIC > 0) finds it with "
    << Pct(100 * l.settings.power) << " chance: its noncentrality √λ reaches √(ln n) + Φ⁻¹("
    << Num(l.settings.power) << ") = " << Num(l.z_needed) << " over " << l.observations
    << " observations (this table's noise, placement scatter and dispersion; the calibration "
       "and the selected effects take what they can). And once it is there it removes, on "
       "average over the outer folds, "
    << Pct(100 * l.settings.min_own_share) << " of each fold's calibrated gap on its held-out "
       "cells"
    << (l.settings.pooled ? ", and " + Pct(100 * l.settings.min_share) + " of their sum" : "")
    << "; or " << Pct(100 * l.settings.min_own_moved_share)
    << (l.settings.pooled ? " and " + Pct(100 * l.settings.min_moved_share) : "")
    << " of the gap's part in the metrics it moves, each weighing by how much it moves them. "
       "The outer folds' agreement is asked too, so the diagnosis needs more still. \"far\" "
       "is the median bias the size adds at "
    << Num(l.far_distance_m) << " m.\n\n"
    << "| effect | axis | below (test; share) | far | above (test; share) | far | note |\n"
    << "|---|---|---|---|---|---|---|\n";
  for (const DetectionLimit& e : l.effects) {
    if (e.param.empty()) continue;
    std::string note;
    if (!e.other.empty()) note = e.other + " held at " + Num(e.other_value);
    if (e.frozen) note += std::string(note.empty() ? "" : "; ") + "found as one of {" + e.effect +
                          ", calibration}";
    auto size = [&](int side) {
      if (!e.searched[side]) return std::string("–");
      return (std::isfinite(e.size[side]) ? Num(e.size[side]) : std::string("beyond the grid")) +
             " (" + Num(e.by_test[side]) + "; " + Num(e.by_share[side]) + ")";
    };
    auto far = [&](int side) {
      if (!std::isfinite(e.far_m[side])) return std::string("–");
      return (std::isfinite(e.size[side]) ? "" : "≥ ") + Signed(e.far_m[side], 2) + " m";
    };
    o << "| " << e.effect << " | " << e.param << " | " << size(0) << " | " << far(0) << " | "
      << size(1) << " | " << far(1) << " | " << note << " |\n";
  }
  o << "\n";
  return o.str();
}

}  // namespace

std::string WidthIntervalNote(const DiagnoseResult& r) {
  for (const TermFit& t : r.selected.terms)
    if (t.profiled)
      return " (a width's interval: the widths whose refit lies within 3.84 of the lowest)";
  return "";
}

std::string ParamsText(const DiagnoseResult& r, const TermFit& t, bool with_ci,
                       bool hide_edges) {
  const Candidate& c = r.candidates[t.term.candidate];
  auto one = [&](int g) {
    std::string s;
    for (size_t a = 0; a < c.axes.size(); ++a) {
      if (hide_edges && t.at_bound[g][a]) {
        s += (s.empty() ? "" : ", ") + c.axes[a].param + " at the grid's edge (not determined)";
        continue;
      }
      s += (s.empty() ? "" : ", ") + c.axes[a].param + " " + Num(t.values[g][a]);
      if (((with_ci && !c.axes[a].discrete) || (c.axes[a].discrete && t.profiled)) &&
          std::isfinite(t.ci_lo[g][a]))
        s += " [" + Num(t.ci_lo[g][a]) + ", " + Num(t.ci_hi[g][a]) + "]";
      if (t.at_bound[g][a]) s += " (grid edge)";
    }
    return s;
  };
  if (t.term.scope == Scope::kShared) return one(0);
  std::string s;
  for (size_t g = 0; g < t.values.size(); ++g)
    s += (s.empty() ? "" : "; ") + ScopeGroupName(r.design, t.term.scope, static_cast<int>(g)) +
         ": " + one(static_cast<int>(g));
  return s;
}

std::string Headline(const DiagnoseResult& r) {
  std::ostringstream o;
  const int km = MedianIndex(r);
  const PlacementEstimate& pe = r.placement;
  // 1. Range error the simulator does not reproduce.
  bool range = false;
  for (const Unexplained& u : r.unexplained) {
    if (u.metric != "median_bias_m" || u.beyond_placement_law) continue;  // those: below
    range = true;
    o << "range: where " << u.where << ", the camera " << Direction(u.size) << " by ";
    if (u.form == "∝ D" || u.form == "∝ D²")  // a law in distance: its far end first
      o << Num(std::fabs(u.size_at_max)) << " m at the far end, growing " << u.form
        << " (mean " << Signed(u.size) << " m, 95 % ± " << Num(1.96 * u.size_se, 2) << " m, "
        << u.cells.size() << " recordings)";
    else
      o << Num(std::fabs(u.size)) << " m (95 % ± " << Num(1.96 * u.size_se, 2) << " m, "
        << u.cells.size() << " recordings; form " << u.form << ")";
    o << "; no registered effect explains it\n";
  }
  if (!range && km >= 0) {
    int beyond = 0;
    for (const Unexplained& u : r.unexplained)
      beyond += u.metric == "median_bias_m" && u.beyond_placement_law;
    o << "range: " << FarGap(r, km);
    o << "the simulator" << (r.steps.empty() ? "" : " with the selected effects")
      << " reproduces the camera's median range within noise and placement scatter";
    if (beyond > 0)
      o << ", but for " << beyond << " test point" << (beyond > 1 ? "s" : "")
        << " beyond the placement law (below)";
    o << "\n";
  }
  o << Unseen(r);
  // 2. Placement.
  if (!pe.empty() && km >= 0) {
    auto law = [&](double d) { return pe.Law(km, kMedianBias, d); };
    o << "placement scatter of a test point: " << Num(pe.a[km], 2) << " m + "
      << Num(100 * pe.b[km], 2) << " % of distance (" << Num(law(4), 2) << " m at 4 m, "
      << Num(law(16), 2) << " m = " << Num(100 * law(16) / 16, 2) << " % at 16 m; REML over "
      << pe.points_used[km] << " test points)\n";
    // The test points beyond it (unexplained.h), farthest reading first.
    std::vector<const Unexplained*> beyond;
    for (const Unexplained& u : r.unexplained)
      if (u.metric == "median_bias_m" && u.beyond_placement_law) beyond.push_back(&u);
    std::sort(beyond.begin(), beyond.end(),
              [](const Unexplained* a, const Unexplained* b) { return a->size > b->size; });
    for (const Unexplained* u : beyond)
      o << "  beyond it: " << u->where << ": " << Signed(u->size, 2) << " m (95 % ± "
        << Num(1.96 * u->size_se, 2) << " m, from the other test points of its light and "
        << "distance; " << (u->size > 0 ? "reads far: over-reads" : "reads near: under-reads")
        << ")\n";
  }
  // 3. Emitter.
  const EmitterGap* worst = nullptr;
  int significant = 0;
  for (const EmitterGap& e : r.noise.emitter) {
    if (std::fabs(e.z) < kEmitterZ) continue;
    ++significant;
    if (!worst || std::fabs(e.z) > std::fabs(worst->z)) worst = &e;
  }
  if (worst)
    o << "emitter: the camera's emitter on − off differs from the simulator's in " << significant
      << " scenario × distance × metric groups; most at "
      << r.design.scenario_names[worst->scenario]
      << " " << Num(worst->distance_m) << " m: " << r.metric_names[worst->k] << " "
      << Signed(worst->mean) << " (z " << Num(worst->z, 2) << ")\n";
  // 4. Which effect.
  if (r.steps.empty()) {
    o << "selected: none (no registered effect earns its place in and out of the outer folds)\n";
  } else {
    o << "selected:";
    for (size_t i = 0; i < r.selected.terms.size(); ++i) {
      const TermFit& t = r.selected.terms[i];
      const std::vector<SizeSpread> none;
      const std::vector<SizeSpread>& spread = i < r.size_spread.size() ? r.size_spread[i] : none;
      int checked = 0, widened = 0;
      for (const SizeSpread& g : spread) checked += g.checked, widened += g.checked && g.widened;
      o << (i ? ";" : "") << " " << r.candidates[t.term.candidate].effect << " ("
        << ParamsText(r, t, checked > 0, true);
      if (checked == 0 && t.profiled) o << ", the width's 95 % interval";
      if (checked > 0) {
        o << ", 95 %";
        const SizeSpread& sp = spread[0];
        if (spread.size() == 1 && sp.widened) {
          o << " from its refits without each outer fold's cells (";
          for (size_t f = 0; f < sp.folds.size(); ++f)
            o << (f ? ", " : "") << Num(sp.folds[f], 3);
          o << "); the fit alone [" << Num(sp.fit_lo, 3) << ", " << Num(sp.fit_hi, 3) << "]";
        } else if (widened > 0) {
          o << ", from its refits without each outer fold's cells where wider than the fit's ("
            << widened << " of " << spread.size() << " scenarios)";
        }
      }
      o << ")";
    }
    o << "\n";
    for (const TermFit& t : r.selected.terms) {
      const int c = t.term.candidate;
      const std::string s = SpreadsEvidenceText(r.spreads, c, r.candidates[c].effect);
      if (!s.empty()) o << s << "\n";
    }
  }
  for (const auto& d : r.dropped) o << "not kept: " << d << "\n";
  for (const Ambiguity& a : r.ambiguous) {
    o << "one of {";
    for (size_t i = 0; i < a.effects.size(); ++i) o << (i ? ", " : "") << a.effects[i];
    o << "}: cannot be told apart here (" << Why(a) << "); would need";
    for (size_t i = 0; i < a.effects.size(); ++i)
      o << (i ? "; " : " ") << a.effects[i] << " " << a.sizes[i];
    o << WithText(r, a) << "\n";
  }
  for (const Unexplained& u : r.unexplained) {
    if (u.metric == "median_bias_m") continue;
    o << "unexplained: " << u.metric << " " << Signed(u.size) << " " << u.unit << " where "
      << u.where << " (form " << u.form << ", " << Pct(u.share_pct) << " of its remaining gap)\n";
  }
  // 5. How far.
  const Nested& n = r.nested;
  if (n.run) {
    o << "how far: held out in outer folds (every fit made without the cells it is judged on), gap "
      << Num(n.baseline.overall) << " -> " << Num(n.simulated.overall)
      << " with the selection simulated (" << Pct(n.shrink_simulated_pct) << " shrink), "
      << Num(n.selected.overall) << " added (" << Pct(n.shrink_heldout_nested_pct) << ")\n";
    // The configured sensor may have been calibrated on this very table (the article's is):
    // the part the effects earn on top of each fold's own calibration, simulated.
    if (std::isfinite(n.gain_simulated))
      o << "how far, effects alone: the folds' calibrated base simulated "
        << Num(n.simulated_calibrated.overall) << " -> " << Num(n.simulated.overall)
        << " with their selections (" << Pct(Shrink(n.simulated_calibrated, n.simulated))
        << ")\n";
  } else {
    o << "how far: gap " << Num(r.baseline.overall) << " -> " << Num(r.selected_heldout.overall)
      << " held out (" << Pct(Shrink(r.baseline_heldout, r.selected_heldout))
      << "); no nested hold-out" << (n.message.empty() ? "" : ": " + n.message) << "\n";
  }
  o << "left: " << r.remaining.size() << " of " << r.design.num_cells()
    << " recordings depart beyond noise and placement scatter\n";
  return o.str();
}

std::string EvidenceMarkdown(const DiagnoseResult& r, const DiagnoseParams& p) {
  std::ostringstream o;
  const PlacementEstimate& pe = r.placement;
  const int kk = static_cast<int>(r.metric_names.size());
  o << "## Noise, placement and the emitter\n\n"
    << "The gap is measured against three variances: the replicate noise σ (emitter on/off twins "
    << "of one placement, with the emitter mismatch removed per scenario and distance), the "
    << "simulation's own scatter σ_sim (the base simulated again with every panel moved sideways "
    << "by less than a pixel: the metrics the region's window decides move by steps), and the "
    << "placement scatter τ of a test point (light, distance, angle), which all its recordings "
    << "share: a random effect, its law in distance estimated by REML about main effects and "
    << "two-factor interactions of light, distance, angle, preset and emitter. z = "
    << "(real − sim) / √(σ² + σ_sim² + τ²); the fits whiten the recordings of one test point "
    << "together.\n\n";
  if (!r.noise.simulation.empty()) {
    o << "| metric | σ at 10 m | σ_sim at 10 m |\n|---|---|---|\n";
    for (int k = 0; k < kk; ++k)
      o << "| " << r.metric_names[k] << " | " << Num(r.noise.scale[k]) << " | "
        << Num(r.noise.simulation[k]) << " |\n";
    o << "\n";
  }
  if (!pe.empty()) {
    o << "| metric | law | τ at 4 m | τ at 8 m | τ at 12 m | τ at 16 m | test points used | "
         "beyond the law |\n|---|---|---|---|---|---|---|---|\n";
    for (int k = 0; k < kk; ++k) {
      const int m = r.design.metrics[k];
      int flagged = 0;
      for (int t = 0; t < pe.num_points; ++t) flagged += pe.flagged[k][t];
      o << "| " << r.metric_names[k] << " | "
        << (m == kMedianBias ? Num(pe.a[k], 3) + " m + " + Num(100 * pe.b[k], 3) + " % of D"
                             : Num(pe.a[k], 3) + " " + InfoOf(m).unit + " × (D/10 m)^" +
                                   Num(InfoOf(m).placement_exponent))
        << " |";
      for (double d : {4.0, 8.0, 12.0, 16.0}) o << " " << Num(pe.Law(k, m, d)) << " |";
      o << " " << pe.points_used[k] << " | " << flagged << " |\n";
    }
    o << "\nTest points beyond the law (p < " << Num(p.placement_alpha) << " / " << pe.num_points
      << ", left out of its estimate and given their own departure as scatter, so that they "
      << "are never taken for a camera effect). The departure is read from the fixed effects "
      << "fitted without the points flagged:\n\n| test point | metric | departure | z |\n"
      << "|---|---|---|---|\n";
    int rows = 0;
    for (int k = 0; k < kk; ++k)
      for (int t = 0; t < pe.num_points; ++t)
        if (pe.flagged[k][t]) {
          ++rows;
          o << "| " << TestPointName(pe, t) << " | " << r.metric_names[k] << " | "
            << Signed(pe.departure[k][t]) << " " << InfoOf(r.design.metrics[k]).unit << " | "
            << Num(pe.departure_z[k][t], 2) << " |\n";
        }
    if (!rows) o << "| none | | | |\n";
  }
  o << "\nEmitter mismatch (the camera's emitter on − off minus the simulator's, mean over the "
    << "test points of a scenario and distance; |z| ≥ " << Num(kEmitterZ) << " listed):\n\n"
    << "| scenario | distance | metric | mismatch | z |\n|---|---|---|---|---|\n";
  int listed = 0;
  for (const EmitterGap& e : r.noise.emitter)
    if (std::fabs(e.z) >= kEmitterZ) {
      ++listed;
      o << "| " << r.design.scenario_names[e.scenario] << " | " << Num(e.distance_m) << " m | "
        << r.metric_names[e.k] << " | " << Signed(e.mean) << " | " << Num(e.z, 2) << " |\n";
    }
  if (!listed) o << "| none | | | | |\n";

  const Nested& n = r.nested;
  o << "\n## Held out, nested\n\n";
  if (!n.run) {
    o << "Not run" << (n.message.empty() ? "." : ": " + n.message + ".") << "\n";
  } else {
    o << "Each outer fold (" << r.holdout << ") is diagnosed from scratch without its cells "
      << "(noise, placement, calibration, φ, scope, selection with its own inner hold-out), "
      << "then its selection predicts the held-out cells, added to the base simulation and "
      << "simulated together at its fitted values. Gaps are in each fold's own units.\n\n"
      << "| outer fold | cells | its selection | held-out deviance, calibrated → selected |\n"
      << "|---|---|---|---|\n";
    for (const NestedFold& f : n.folds) {
      std::string sel;
      for (const auto& s : f.selected) sel += (sel.empty() ? "" : ", ") + s;
      o << "| " << f.held << " | " << f.cells << " | " << (sel.empty() ? "none" : sel) << " | "
        << Num(f.deviance_calibrated) << " → " << Num(f.deviance_selected) << " |\n";
    }
    o << "\n" << GapTableHeader("held-out gap", r.metric_names);
    auto row = [&](const std::string& name, const GapStat& g) {
      o << GapTableRow(name, g, r.metric_names.size());
    };
    row("baseline", n.baseline);
    row("calibrated", n.calibrated);
    row("selection added", n.selected);
    if (n.simulated.count > 0) row("selection simulated", n.simulated);
    o << "\nShrink held out: " << Pct(n.shrink_simulated_pct) << " simulated (the headline), "
      << Pct(n.shrink_heldout_nested_pct) << " added.\n";
  }
  o << "\n## Named, not selected\n\n";
  if (r.ambiguous.empty() && r.dropped.empty()) o << "- none\n";
  for (const Ambiguity& a : r.ambiguous) {
    o << "- one of {";
    for (size_t i = 0; i < a.effects.size(); ++i) o << (i ? ", " : "") << a.effects[i];
    o << "} (" << Why(a) << "):";
    for (size_t i = 0; i < a.effects.size(); ++i)
      o << (i ? ";" : "") << " " << a.effects[i] << " would need " << a.sizes[i];
    o << WithText(r, a) << "\n";
  }
  for (const auto& d : r.dropped) o << "- not kept: " << d << "\n";
  o << "\n## Not explained by any registered effect\n\n";
  if (r.unexplained.empty())
    o << "No metric's remaining gap lies in a group of cells beyond chance (its best group "
         "against tables with their test points permuted, p < "
      << Num(p.alpha) << " / metrics), and no test point is placed beyond the scatter's law.\n";
  else
    o << "A metric's rest is listed where its best group of cells departs beyond chance (against "
         "tables with their test points permuted as wholes, p < "
      << Num(p.alpha) << " / metrics). The median bias's rest shared by every recording "
      << "(constant, ∝ D or ∝ D², or a step from a distance on), or by every recording of one "
      << "light, is judged against signs drawn for test points as wholes, and a test point "
      << "beyond the placement law is listed too.\n\n"
      << "| metric | where | size [95 %] | form | at the far end | share of its rest | χ² / "
         "cells | p |\n|---|---|---|---|---|---|---|---|\n";
  for (const Unexplained& u : r.unexplained)
    o << "| " << u.metric << " | " << u.where << " | " << Signed(u.size) << " ± "
      << Num(1.96 * u.size_se, 2) << " " << u.unit << " | " << u.form << " | "
      << Signed(u.size_at_max) << " | " << Pct(u.share_pct) << " | " << Num(u.chi2) << " / "
      << u.df << " | " << Num(u.p_value, 2) << " |\n";
  o << "\n" << LimitsMarkdown(r);
  return o.str();
}

}  // namespace depthbias::gap::text
