#include "gap/diagnose.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "gap/nested.h"
#include "gap/report_util.h"
#include "gap/select.h"
#include "gap/unexplained.h"
#include "gap/votes.h"

namespace depthbias::gap {
namespace {

std::string Num(double v) {
  std::ostringstream s;
  s << std::setprecision(3) << v;
  return s.str();
}

}  // namespace

bool DiagnoseParams::IsValid(std::string* why) const {
  if (!simulate.IsValid(why) || !fit.IsValid(why)) return false;
  if (!(confounded_r > 0 && confounded_r <= 1) || !(absorb_r > 0 && absorb_r <= 1) ||
      !(alpha > 0 && alpha < 1) ||
      max_selected < 0 || max_selected > 10 ||
      !(min_effect_shrink_pct >= 0 && min_effect_shrink_pct < 100) ||
      !(min_own_shrink_pct >= 0 && min_own_shrink_pct < 100) ||
      !(min_moved_shrink_pct >= 0 && min_moved_shrink_pct < 100) ||
      !(min_own_moved_shrink_pct >= 0 && min_own_moved_shrink_pct < 100)) {
    if (why)
      *why = "need confounded_r and absorb_r in (0, 1], alpha in (0, 1), max_selected in "
             "[0, 10], min_effect_shrink_pct, min_own_shrink_pct, min_moved_shrink_pct and "
             "min_own_moved_shrink_pct in [0, 100)";
    return false;
  }
  return true;
}

const EffectResult* DiagnoseResult::Effect(const std::string& name) const {
  for (const auto& e : effects)
    if (e.name == name) return &e;
  return nullptr;
}

bool DiagnoseResult::Selected(const std::string& name) const {
  for (const auto& s : steps)
    if (s.effect == name) return true;
  return false;
}

bool DiagnoseResult::ConfoundedWith(const std::string& a, const std::string& b) const {
  for (const auto& c : confounded)
    if ((c.a == a && c.b == b) || (c.a == b && c.b == a)) return true;
  return false;
}

sim::EffectSpec EffectOf(const Simulations& sims, const TermFit& term, int group) {
  return SpecAt(sims.surfaces[term.term.candidate].candidate, term.values[group]);
}

DiagnoseResult Diagnose(const std::vector<records::PanelMetrics>& real,
                        const sim::SimParams& base, const DiagnoseParams& params) {
  DiagnoseResult r;
  std::string why;
  Design design;
  std::vector<Candidate> candidates;
  if (!params.IsValid(&why) || !BuildDesign(real, &design, &why) ||
      !SelectCandidates(params.candidates, &candidates, &why)) {
    r.message = why;
    return r;
  }
  SimulateOptions options = params.simulate;
  options.replica = static_cast<int>(design.pairs.size()) < kMinReplicatePairs;
  try {
    const Simulations sims = params.Simulate(base, design, candidates, options);
    return DiagnoseWith(design, sims, base, params);
  } catch (const std::exception& e) {
    r.message = e.what();
    return r;
  }
}

namespace {

// The selected terms refitted without each fold's cells (SizeSpread, one per group: the shared
// value, or each scenario's), and their intervals widened to the refits' spread.
std::vector<std::vector<SizeSpread>> SpreadOverFolds(const GapModel& model,
                                                     const std::vector<int>& fold, int num_folds,
                                                     ModelFit* selected) {
  const size_t n_terms = selected->terms.size();
  std::vector<std::vector<SizeSpread>> out(n_terms);
  std::vector<Term> terms;
  std::vector<char> eligible(n_terms, 0);
  for (size_t i = 0; i < n_terms; ++i) {
    const TermFit& t = selected->terms[i];
    terms.push_back(t.term);
    const Candidate& c = model.surface(t.term.candidate).candidate;
    out[i].resize(t.values.size());
    eligible[i] = c.axes.size() == 1 && !c.axes[0].discrete && !t.values.empty();
    for (const auto& v : t.values) eligible[i] = eligible[i] && v.size() == 1;
  }
  if (std::find(eligible.begin(), eligible.end(), 1) == eligible.end()) return out;
  std::vector<std::vector<std::vector<double>>> u(n_terms);  // [term][group][refit]
  for (size_t i = 0; i < n_terms; ++i) u[i].resize(out[i].size());
  for (int f = 0; f < num_folds; ++f) {
    std::vector<char> train(fold.size(), 0);
    bool held = false;
    for (size_t c = 0; c < fold.size(); ++c) {
      train[c] = fold[c] != f;
      held = held || fold[c] == f;
    }
    if (!held) continue;
    const ModelFit refit = FitTerms(model, terms, train, selected);
    if (!refit.success || refit.terms.size() != n_terms) continue;
    for (size_t i = 0; i < n_terms; ++i) {
      const TermFit& t = refit.terms[i];
      if (!eligible[i] || t.values.size() != out[i].size()) continue;
      for (size_t g = 0; g < t.values.size(); ++g) {
        if (t.at_bound[g][0]) continue;
        out[i][g].folds.push_back(t.values[g][0]);
        u[i][g].push_back(model.ToCoord(t.term.candidate, 0, t.values[g][0]));
      }
    }
  }
  for (size_t i = 0; i < n_terms; ++i) {
    if (!eligible[i]) continue;
    TermFit* term = &selected->terms[i];
    const int cand = term->term.candidate;
    for (size_t g = 0; g < out[i].size(); ++g) {
      SizeSpread& s = out[i][g];
      const std::vector<double>& ug = u[i][g];
      const int n = static_cast<int>(ug.size());
      if (n < 3) continue;
      s.checked = true;
      double mean = 0, ss = 0;
      for (double v : ug) mean += v / n;
      for (double v : ug) ss += (v - mean) * (v - mean);
      s.se_folds = std::sqrt((n - 1.0) / n * ss);
      s.t = StudentT975(n - 1);
      s.fit_lo = term->ci_lo[g][0];
      s.fit_hi = term->ci_hi[g][0];
      const double x = model.ToCoord(cand, 0, term->values[g][0]);
      const double half = s.t * s.se_folds;
      double lo = model.ToCoord(cand, 0, s.fit_lo), hi = model.ToCoord(cand, 0, s.fit_hi);
      if (!std::isfinite(lo)) lo = x;
      if (!std::isfinite(hi)) hi = x;
      if (!(x - lo >= half && hi - x >= half)) {
        s.widened = true;
        term->ci_lo[g][0] = model.FromCoord(cand, 0, std::min(lo, x - half));
        term->ci_hi[g][0] = model.FromCoord(cand, 0, std::max(hi, x + half));
      }
    }
  }
  return out;
}

}  // namespace

DiagnoseResult DiagnoseWith(const Design& design, const Simulations& sims,
                            const sim::SimParams& base, const DiagnoseParams& params) {
  DiagnoseResult r;
  std::string why;
  if (!params.IsValid(&why)) {
    r.message = why;
    return r;
  }
  if (!sims.Matches(design)) {
    r.message = "the simulations are not of this table's cells and metrics";
    return r;
  }
  r.design = design;
  for (const Surface& surf : sims.surfaces) r.candidates.push_back(surf.candidate);
  for (int m : design.metrics) r.metric_names.push_back(InfoOf(m).name);
  r.holdout = HoldoutName(params.holdout);
  r.simulations = sims.runs;
  std::vector<int> fold;
  if (!Folds(design, params.holdout, &fold, &r.folds, &why)) {
    r.message = why;
    return r;
  }
  try {
    r.noise = EstimateNoise(design, sims);
    if (params.placement)
      r.placement = EstimatePlacement(design, sims, r.noise,
                                      std::vector<char>(design.num_cells(), 1),
                                      params.placement_alpha);
  } catch (const std::exception& e) {
    r.message = e.what();
    return r;
  }
  GapModel model(design, sims, r.noise, params.fit, &r.placement);
  const int cells = design.num_cells();
  const std::vector<char> all(cells, 1);
  std::vector<char> held(cells, 0);
  for (int c = 0; c < cells; ++c) held[c] = fold[c] >= 0;

  // 1–2. The baseline gap and where it lies.
  r.sim_base = sims.base;
  r.z_base = Scaled(model, sims.base);
  r.baseline = Stat(model, r.z_base, all);
  r.baseline_heldout = Stat(model, r.z_base, held);
  r.localization = Localize(design, r.z_base, params.alpha);

  // 3. The calibrated base, every candidate alone, forward selection.
  Selection sel = Select(model, r.placement, all, fold, r.folds, params);
  if (!sel.success) {
    r.message = sel.message;
    return r;
  }
  const ModelFit& m0 = sel.m0;
  r.dispersion = sel.dispersion;
  r.calibration = m0;
  {
    const std::vector<double> phi = model.dispersion();
    model.SetDispersion(sel.dispersion);
    r.calibration_in = Stat(model, Scaled(model, model.Predict(m0)), all);
    r.calibration_heldout = Stat(model, Scaled(model, sel.m0_ho.mu), sel.m0_ho.cells);
    model.SetDispersion(phi);
  }
  r.configured = sims.sensor.scenarios;
  r.calibrated = sims.sensor.scenarios;
  {
    const auto per = SelectedParams(sims, sim::SimParams(), m0, design);
    for (int s = 0; s < design.num_scenarios(); ++s)
      r.calibrated[s] = per[s].sensor.scenarios[s];
  }
  r.effects = sel.effects;
  r.confounded = sel.confounded;
  r.correlations = sel.correlations;
  r.steps = sel.steps;
  r.dropped = sel.dropped;
  r.spreads = sel.spreads;
  r.ambiguous = sel.ambiguous;
  if (!sel.message.empty()) r.message = sel.message;
  ModelFit current = sel.current;
  HeldOut current_ho = sel.current_ho;

  auto keep_only = [&](const std::vector<char>& keep) {
    if (!KeepSteps(model, m0, keep, all, fold, r.folds, &r.steps, &current, &current_ho))
      r.message = "the refit without the dropped effects failed";
  };
  auto sizes_of = [&](const std::vector<std::string>& names) {  // each effect's size alone
    std::vector<std::string> out;
    for (const std::string& e : names)
      for (size_t j = 0; j < sel.effects.size(); ++j)
        if (sel.effects[j].name == e)
          out.push_back(SizeText(sims.surfaces[j].candidate, sel.effects[j].fit));
    return out;
  };

  // 4. The outer hold-out around all of it; an effect selected here stays only if it earns
  // there (selected in at least half of the outer folds, and the folds' selections gain on
  // their held-out cells).
  if (params.nested) {
    r.nested = RunNested(design, sims, base, params, fold, r.folds, model);
    if (r.nested.run && !r.steps.empty()) {
      std::vector<char> keep(r.steps.size(), 0);
      const double sel_need[2] = {params.min_effect_shrink_pct, params.min_moved_shrink_pct};
      const double own_need[2] = {params.min_own_shrink_pct, params.min_own_moved_shrink_pct};
      // Each effect's own part first: in each outer fold, the share of that fold's calibrated
      // gap it brings back when left out of the fold's selection (0 where the fold does not
      // select it), averaged over the folds, read both ways. Each held-out distance is one
      // piece of evidence: pooled, the fold of the largest gap would decide alone (a camera
      // whose emitter adds no texture holds 90 % of a user's unit's gap in valid_pct at 4 m,
      // where an offset of −0.25 px, 50–65 % of each other fold's gap, came to 6 % of the
      // pooled one).
      std::vector<FoldVote> own(r.steps.size());
      std::vector<std::string> own_earners;
      // A range law fitted at its grid's edge (not its parameter's own bound) has no size, and
      // the table's law may lie beyond every grid, where the laws' forms are not compared: on
      // the article's rows an offset injected at 2 and 3 times its limit (−1.31 and −1.96 px,
      // beyond the offset's nodes at ±1 px) was kept as a depth scale at its edge of +20 % at
      // 2 and 3 seeds of 5 (diagnose_gap --inject-times). Such a law is not kept; it is named
      // "one of" with the range law whose signature correlates with it most (|r| ≥ 0.5) and
      // that earns alone, where the table does not keep that one. Like a rival of the folds, it is
      // decided with the effect in the set read together, where it would be kept. Without such a
      // law it is not kept either, and what it would have taken stays in the remaining gap,
      // named where it lies (unexplained): at 3 times the limit (seed 1, −1.87 px, beyond the
      // offset's last node at −1.5 px) the offset no longer fits and a scale was kept at +20 %,
      // its interval [−0.15, 0.5]. Whether the law's fit is at its grid's edge, its rival, r, and
      // whether the rival's own fit alone sits at its grid's edge too; or nothing.
      struct Edge {
        bool at_edge = false;
        std::string rival;
        double r = 0;
        bool rival_at_edge = false;
      };
      auto at_edge = [](const TermFit& t) {
        for (const auto& group : t.at_bound)
          if (std::find(group.begin(), group.end(), 1) != group.end()) return true;
        return false;
      };
      std::vector<Edge> edge_rival(r.steps.size());
      std::vector<char> edge_named(r.steps.size(), 0);
      auto EdgeRival = [&](const std::string& e) -> Edge {
        const TermFit* fit = nullptr;
        for (const TermFit& t : current.terms)
          if (sims.surfaces[t.term.candidate].candidate.effect == e) fit = &t;
        if (!fit || !sims.surfaces[fit->term.candidate].candidate.range_law || !at_edge(*fit))
          return {};
        Edge best;
        best.at_edge = true;
        for (const Confounded& c : sel.correlations) {
          const std::string other = c.a == e ? c.b : c.b == e ? c.a : "";
          if (other.empty() || !(std::fabs(c.correlation) >= 0.5) ||
              std::fabs(c.correlation) <= std::fabs(best.r))
            continue;
          for (size_t j = 0; j < sel.effects.size(); ++j)
            if (sel.effects[j].name == other && sel.effects[j].earns &&
                sims.surfaces[j].candidate.range_law)
              best = {true, other, c.correlation, at_edge(sel.effects[j].fit)};
        }
        return best;
      };
      for (size_t i = 0; i < r.steps.size(); ++i) {
        const std::string& e = r.steps[i].effect;
        FoldVote& w = own[i] = VoteOf(r.nested, e, own_need);
        // A rival (FindRival): the held-out evidence does not prefer the effect selected here
        // (on the article's rows an injected −0.95 px offset was kept as a +19.7 % scale, one
        // fold choosing each alone, 24 % and 38 % of its gap, and one both; at another seed the
        // scale was selected and dropped, one fold choosing it, while three chose the offset).
        // An effect that would be kept is then not, the others are read again without it, and
        // the pair is named "one of".
        FindRival(r.nested, sel.correlations, r.steps, e, own_need, &w);
        edge_rival[i] = EdgeRival(e);
        if (w.earns) own_earners.push_back(e);
      }
      // Then the effects that earn their own part, together: the folds' selections restricted
      // to them, simulated again on the held-out cells. An effect a fold selected that the
      // table does not keep (it loses held out, or too few folds select it) no longer decides
      // for the others: on the article's table with a disparity offset of −0.98 px injected,
      // three folds of four selected the offset (its own part 20 % of their gap), and the fold
      // holding 12 m out an edge mixing that lost 326 of its 769 simulated Σz²: the folds'
      // selections removed 9.2 % of the calibrated gap and the offset was dropped.
      // The set read together is brought to the one kept: an effect that earns its own part by
      // one reading and the joint part only by the other is dropped, and the others are read
      // again without it.
      std::vector<std::string> together = own_earners;
      std::vector<char> contested(r.steps.size(), 0);  // named "one of" with its rival
      const bool simulated = !std::isnan(r.nested.gain_simulated);
      for (int pass = 0;; ++pass) {
        if (!together.empty())
          RestrictNested(design, sims, base, params, fold, model, together, &r.nested);
        const bool restricted = !r.nested.kept.empty();
        const double joint_gain =
            restricted ? r.nested.gain_simulated_kept : r.nested.gain_simulated;
        const GapStat& joint = restricted ? r.nested.simulated_kept : r.nested.simulated;
        // The selection's part, pooled over the folds: of the whole calibrated gap [0], and of
        // its part in the metrics the selections move [1] (MovedShare).
        const double calibrated = r.nested.simulated_calibrated.overall;
        const double sel_pct[2] = {
            calibrated > 0 ? 100 * (calibrated - joint.overall) / calibrated : NAN,
            100 * (restricted ? r.nested.share_moved_kept : r.nested.share_moved)};
        std::vector<std::string> kept;
        std::vector<std::string> why(r.steps.size());
        for (size_t i = 0; i < r.steps.size(); ++i) {
          const FoldVote& w = own[i];
          // The guards read shares of the calibrated base's held-out Σz², noise included, not
          // of its excess over the noise (Shrink): on a table without effect the excess is
          // small, and a tenth of it is earned by chance (3 of 20 null tables at seed 1 kept an
          // offset or a range-vs-depth weight that removed 2.7–6 % of the whole). An effect
          // earns by either reading, each with its own floors (DiagnoseParams): a share of the
          // whole gap, or a larger share of the gap in the metrics it moves. Read in the whole
          // only, a range law is judged against gaps it cannot touch: on the article's table
          // the held-out gap sits in the emitter's valid_pct and the 4 m plane_std, and a depth
          // scale of +12 % (1.8 m at 16 m) would not remove a tenth of it.
          bool by[2] = {false, false};
          for (int m = 0; m < 2; ++m)
            by[m] = sel_pct[m] >= sel_need[m] &&
                    (!w.known || w.count == 0 || w.pct[m] >= own_need[m]);
          // The folds' selections must earn on their held-out cells as the simulator
          // reproduces them; as the fits predict them only where the folds were not simulated.
          // The fits' prediction interpolates the candidates' surfaces, and where the two
          // disagree the surfaces are wrong there, not the effect: a depth scale of 0.06 at
          // seed 3, selected by all four folds and simulated, removed 46 % of their calibrated
          // gap, while the fold holding 4 m out predicted a tilt 55 times the noise at 4 m from
          // a surface whose node at −0.12 loses the sunset HA panel (its tilt 67°), spread by
          // the average over placement (smooth.h) over the line.
          const bool held_out_earns =
              simulated ? joint_gain > 0 && (by[0] || by[1]) : r.nested.gain > 0;
          // Contested once read kept with its rival beside it, it stays so when the others are
          // read again without it. One dropped for too few folds is contested by its rival
          // whatever the selections earn together: that rival is not among them.
          contested[i] |= !w.rival.empty() && (held_out_earns || !w.earns);
          const bool edge = edge_rival[i].at_edge, edge_rival_named = !edge_rival[i].rival.empty();
          const bool read_together =
              std::find(together.begin(), together.end(), r.steps[i].effect) != together.end();
          edge_named[i] |=
              edge_rival_named && read_together && held_out_earns && w.earns && w.rival.empty();
          keep[i] = held_out_earns && w.earns && w.rival.empty() && !edge;
          if (keep[i]) {
            kept.push_back(r.steps[i].effect);
            continue;
          }
          auto need = [&](double v) { return " (" + Num(v) + " % needed)"; };
          why[i] =
              r.steps[i].effect + " (selected in " + std::to_string(w.count) + " of " +
              std::to_string(r.nested.folds.size()) + " outer folds; the folds' selections gain " +
              Num(r.nested.gain) + " held out" +
              (simulated ? std::string(restricted ? "; restricted to those carrying their own "
                                                    "part, "
                                                  : ", ") +
                               Num(joint_gain) + " simulated, removing " + Num(sel_pct[0]) +
                               " % of the calibrated base's gap" + need(sel_need[0]) + " and " +
                               Num(sel_pct[1]) + " % of its part in the metrics they move" +
                               need(sel_need[1])
                         : std::string()) +
              (std::isnan(w.pct[0])
                   ? std::string()
                   : "; left out of them, an outer fold's calibrated gap comes back by " +
                         Num(w.pct[0]) + " % on average" + need(own_need[0]) +
                         ", its part in the metrics it moves by " + Num(w.pct[1]) + " %" +
                         need(own_need[1])) +
              (w.rival.empty() ? std::string()
                               : "; " + w.rival + " chosen " + (w.earns ? "at least as" : "more") +
                                     " often, in " +
                                     std::to_string(w.rival_count) + ", r = " + Num(w.rival_r)) +
              (!edge ? std::string()
                     : "; fitted at its grid's edge, its size not determined" +
                           (edge_rival_named ? ", beside " + edge_rival[i].rival +
                                                   ", r = " + Num(edge_rival[i].r)
                                             : std::string())) +
              ")";
        }
        if (kept.empty() || kept == together || pass == 2) {
          for (const std::string& w : why)
            if (!w.empty()) r.dropped.push_back(w);
          break;
        }
        together = kept;  // a strict part of the set read: read it again
      }
      std::vector<std::string> read;  // the effects the keep rule read, in its order
      for (const SelectionStep& st : r.steps) read.push_back(st.effect);
      keep_only(keep);
      for (size_t i = 0; i < own.size(); ++i) {
        const auto named_or_kept = [&](const std::string& a, const std::string& b) {
          for (const Ambiguity& m : r.ambiguous)
            if (std::count(m.effects.begin(), m.effects.end(), a) &&
                std::count(m.effects.begin(), m.effects.end(), b))
              return true;
          return r.Selected(b);
        };
        if (edge_named[i] && !contested[i] && !named_or_kept(read[i], edge_rival[i].rival)) {
          const Edge& edge = edge_rival[i];
          Ambiguity pair{{read[i], edge.rival}, {}, edge.r, "", {}};
          pair.sizes = sizes_of(pair.effects);
          if (pair.sizes.size() != 2) continue;
          pair.why = read[i] + " is fitted at its grid's edge" +
                     (edge.rival_at_edge ? std::string(", and so is ") + edge.rival + " alone" : "") +
                     ": the law may lie beyond the grid, where the two are not compared, r = " +
                     Num(edge.r);
          r.ambiguous.push_back(pair);
          continue;
        }
        if (!contested[i]) continue;
        Ambiguity rival{{read[i], own[i].rival}, {}, own[i].rival_r, "", {}};
        rival.sizes = sizes_of(rival.effects);
        if (rival.sizes.size() != 2) continue;
        rival.why = "the outer folds choose " + own[i].rival +
                    (own[i].earns ? " at least as" : " more") + " often: " +
                    rival.effects[0] + " in " + std::to_string(own[i].count) + ", " +
                    own[i].rival + " in " + std::to_string(own[i].rival_count) + " of " +
                    std::to_string(r.nested.folds.size()) + ", r = " + Num(own[i].rival_r);
        r.ambiguous.push_back(rival);
      }
    }
  }
  std::stable_sort(r.effects.begin(), r.effects.end(),
                   [](const EffectResult& a, const EffectResult& b) {
                     return a.heldout_gain > b.heldout_gain;
                   });

  // Named, not selected: an effect along the calibration that earns alone, and an effect
  // confounded with a selected one that earns alone.
  for (size_t i = 0; i < sel.effects.size(); ++i) {
    const EffectResult& e = sel.effects[i];
    const Candidate& cand = sims.surfaces[i].candidate;
    if (!e.earns) continue;
    if (model.Absorbs(static_cast<int>(i))) {
      const bool sigma = model.Absorbs(static_cast<int>(i)) & 1;
      std::string need;
      for (int s = 0; s < design.num_scenarios(); ++s)
        need += (s ? " / " : "") +
                Num(sigma ? r.calibrated[s].sigma_d_px : r.calibrated[s].invalid_prob);
      Ambiguity a{{e.name, sigma ? "calibration:sigma_d" : "calibration:hole_prob"},
                  {SizeText(cand, e.fit), (sigma ? "sigma_d_px " : "invalid_prob ") + need},
                  std::sqrt(sigma ? sel.r2_sigma[i] : sel.r2_p[i]), "", {}};
      // What the selection reads were this effect the cause: one fit of the terms that act
      // together, the window at their joint depth (fit.h, 1a; a drift beside an offset).
      if (!current.terms.empty()) {
        // Two rounds against the simulated selection: on an offset beside a drift the first
        // moved it from 0.11 to 0.139 px (0.15 injected, seed 1002), the second to 0.137, a
        // third nowhere.
        const ModelFit with = SimulatedBeside(model.JointWindow(), current, e.fit, all, fold,
                                              r.folds, base, params.simulate, 2, &r.simulations,
                                              &a.selection_with_rounds);
        if (with.success) a.selection_with = with.terms;  // the named effect last
      }
      r.ambiguous.push_back(std::move(a));
    }
    for (const auto& c : sel.confounded) {
      const std::string other = c.a == e.name ? c.b : c.b == e.name ? c.a : "";
      if (other.empty() || other.rfind("calibration:", 0) == 0 || !r.Selected(other)) continue;
      for (size_t j = 0; j < sel.effects.size(); ++j)
        if (sel.effects[j].name == other)
          r.ambiguous.push_back({{other, e.name},
                                 {SizeText(sims.surfaces[j].candidate, sel.effects[j].fit),
                                  SizeText(cand, e.fit)},
                                 c.correlation, "", {}});
    }
  }

  // Named, not selected: two effects the outer folds split between (FoldSplits): the table
  // shows a law of that kind without telling which (the field campaign with a +3.6 % scale
  // injected beside its own offset, at seed 1).
  if (params.nested && r.nested.run && !r.nested.folds.empty()) {
    const double own_need[2] = {params.min_own_shrink_pct, params.min_own_moved_shrink_pct};
    for (Ambiguity& split :
         FoldSplits(r.nested, sel.correlations, r.steps, r.ambiguous, own_need, sizes_of))
      r.ambiguous.push_back(std::move(split));
  }

  // How far, and what is left.
  r.selected = current;
  {
    GapModel at_phi = model;  // the selection's dispersion
    at_phi.SetDispersion(r.dispersion);
    r.size_spread = SpreadOverFolds(at_phi, fold, r.folds, &r.selected);
    // Every effect listed the same, alone: the fit's own interval reads low where few test
    // points carry an effect (a range law at the far distance: lib/gap/README.md).
    for (EffectResult& e : r.effects) {
      ModelFit alone;
      alone.terms = {e.fit};
      SpreadOverFolds(at_phi, fold, r.folds, &alone);
      e.fit.ci_lo = alone.terms[0].ci_lo;
      e.fit.ci_hi = alone.terms[0].ci_hi;
    }
    ProfileDiscreteAxes(at_phi, all, &r.selected);
    // The shares an effect must remove, of the gaps the keep rule reads (above): each outer
    // fold's calibrated base simulated on its held-out cells, or the table's calibrated gap
    // without the nested hold-out.
    LimitSettings ls;
    ls.min_share = params.min_effect_shrink_pct / 100;
    ls.min_own_share = params.min_own_shrink_pct / 100;
    ls.min_moved_share = params.min_moved_shrink_pct / 100;
    ls.min_own_moved_share = params.min_own_moved_shrink_pct / 100;
    ls.pooled = current.terms.empty();
    const std::vector<double>& zsc = r.nested.z_simulated_calibrated;
    const int kk = design.num_metrics();
    if (r.nested.run && zsc.size() == static_cast<size_t>(model.num_obs())) {
      ls.fold = fold;
      ls.fold_gap_sq.assign(r.folds, std::vector<double>(kk, 0.0));
      for (size_t o = 0; o < zsc.size(); ++o) {
        const int f = fold[o / kk];
        if (model.valid(o) && std::isfinite(zsc[o]) && f >= 0 && f < r.folds)
          ls.fold_gap_sq[f][o % kk] += zsc[o] * zsc[o];
      }
    } else if (r.calibration_in.count > 0) {
      ls.fold.assign(design.num_cells(), 0);
      ls.fold_gap_sq.emplace_back();
      for (int k = 0; k < kk; ++k)
        ls.fold_gap_sq[0].push_back(r.calibration_in.n[k] ? r.calibration_in.mean_sq[k] *
                                                                r.calibration_in.n[k]
                                                          : 0.0);
    }
    r.limits = FindDetectionLimits(at_phi, all, ls, &current);
  }
  r.z_selected = Scaled(model, model.Predict(current));
  r.z_selected_heldout = Scaled(model, current_ho.mu);
  r.selected_in = Stat(model, r.z_selected, all);
  r.selected_heldout = Stat(model, r.z_selected_heldout, current_ho.cells);
  r.remaining = SignificantCells(design, r.z_selected, params.alpha);
  RestParams rest;
  rest.alpha = params.alpha;
  r.unexplained = DescribeRest(model, model.Predict(current), r.placement, rest);
  const int phases = params.simulate.lateral_phase_px > 0 ? 2 : 1;  // SimulateSelection's runs
  if (params.verify) {
    try {
      const std::vector<double> v = SimulateSelection(
          SelectedParams(sims, base, current, design), design, base, params.simulate);
      r.z_verified = Scaled(model, v);
      r.verified_in = Stat(model, r.z_verified, all);
      r.verified = true;
      r.simulations += phases;
    } catch (const std::exception& e) {
      r.message = std::string("verification skipped: ") + e.what();
    }
  }
  if (r.nested.run) r.simulations += r.nested.folds.empty() ? 0 : phases;
  r.success = true;
  return r;
}

}  // namespace depthbias::gap
