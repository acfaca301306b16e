#pragma once
// Proof on tables whose answer is known, made the way a campaign is made: every test point
// (light, distance, angle) is one placement of the panel, off by a random range error shared by
// its recordings (2 % of the distance by default), and the table holds one or more effects the
// base model lacks: each registered effect at a small and a large size, an effect in one light
// only, correlated pairs, an effect no larger than one test point's placement scatter, effects
// outside the registry (applied to the simulated rows, never registered), no effect at all, a
// user's own unit (one light, one preset, 16 test points × emitter on/off). Each table is
// diagnosed with the base model and judged on what the diagnosis publishes (its gap.json).
//
// A case passes only when (JudgeCase):
//  - the selected set equals the injected set (outside the registry: nothing is selected, and
//    `unexplained` names cells of the right test points and no others);
//  - every injected parameter comes back within 20 % of its departure from the neutral value,
//    scenario by scenario (zero where the effect is absent; whole-pixel widths exactly);
//  - where the effect is in the registry, the shrink the simulator reproduces with the selected
//    effects switched on, on held-out cells of the outer loop (how_far.shrink_simulated_pct),
//    is at least 70 %.
// A criterion whose field the diagnosis does not publish is not met. A null case passes when
// nothing is selected; the null suite when at least 19 of 20 seeds pass.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "gap/diagnose.h"

namespace depthbias::gap {

// A registered effect in a case's table: in every cell, or only in the cells of one light.
struct Injection {
  std::string effect;
  std::map<std::string, double> params;
  std::string only_light;  // "": every cell
};

// An effect outside the registry, applied to the simulated rows (sim's registry never holds it).
struct OutsideEffect {
  enum Kind {
    kNone,
    // A far over-read growing with the square of the distance that leaves the spread alone
    // (multipath off the ground, a reflector behind the panel): median_m and mean_m +=
    // coef·(D / 10 m)² [m]; a disparity offset would also widen plane_std by its Z² law.
    kFarOverRead,
    // One test point read coef metres far in every recording (a wrong tape mark, a reflective
    // object beside it): median_m and mean_m += coef at (light, distance_m, angle_deg).
    kPointStep,
    // A far over-read that starts at a range (a return from behind the panel, off a reflector
    // or the ground, that the camera mixes in beyond some distance): median_m and mean_m +=
    // coef at distances ≥ from_distance_m, nothing nearer. No registered effect is a step in
    // distance: a disparity offset grows as D², a depth scale as D.
    kFarStep,
  } kind = kNone;
  double coef = 0;
  std::string light;
  double distance_m = 0, angle_deg = 0;
  double from_distance_m = 0;  // kFarOverRead, kFarStep: cells at or beyond this distance are
                               // "right" (kFarStep: and the only ones moved)
};

// What an outside effect adds to a row's median_m and mean_m [m] (its spreads stay): the one
// definition the simulated tables and the real ones it is injected into share.
double OutsideShiftM(const OutsideEffect& o, const records::PanelMetrics& row);

struct WithheldCase {
  std::string name;           // "disparity_offset small", "null 3", ...
  std::string family;         // registry, sunset_only, pair, noise_floor, outside, null, unit
  std::vector<Injection> injected;
  OutsideEffect outside;
  double placement_pct = 2.0;  // σ of each test point's range error, % of its distance
  bool unit = false;           // one light (daylight), one preset (HA): 32 rows
  // Injected by its physics into a real table's rows (RealInjectionCases), not simulated.
  bool on_real = false;
  // on_real, a size below the limit the real table's own report gives: it may go unseen (see
  // JudgeCase).
  bool may_go_unseen = false;
};

// The strict suite: every registered effect at two sizes, a sunset-only disparity offset,
// offset + drift, offset + scale, a disparity offset no larger than one far test point's
// placement scatter, effects outside the registry (a far over-read ∝ D², one test point read
// far, over-reads from 12 m on, from 8 m on and at 16 m alone), a user's unit with a disparity
// offset, the projector's texture scaled (all under 2 % placement scatter).
std::vector<WithheldCase> DefaultWithheldCases();
// A user's campaign recorded as bags of field scenes (scripts/make_field_campaign.py: daylight,
// HA, 16 test points × emitter off/on, each disparity read −0.25 px too large), measured by
// panel_extract: the injected set is that offset.
WithheldCase FieldCampaignCase();
// Effects injected by their physics into a real table (the article's 128 rows, a user's
// campaign): the table keeps the camera's own departures, placements, noise and outliers, which
// no simulator of ours made. A disparity offset and a depth scale in the over-reading
// (dangerous) direction, each at `times` the limit the table's own diagnosis publishes on that
// side (`limits`; 3 significant digits), named "LABEL + effect (1.5 × its limit)" (the multiple
// as %g); an effect whose limit that way lies beyond its grid is left out. Below 1 × its limit an
// effect may go unseen (WithheldCase::may_go_unseen); from 1 × on it must be selected.
// Then, at each multiple from 1 on, an effect outside the registry: a far over-read ∝ D² in
// the median and the mean alone, as large at the table's farthest distance as the offset at
// that multiple of its limit reads there (DetectionLimit::far_m), named "LABEL + far over-read
// ∝ D², outside (1.5 × its limit)": the offset's median without what an offset does to the
// spreads, which must not be pinned on the offset or on any law the table holds.
std::vector<WithheldCase> RealInjectionCases(const DetectionLimits& limits,
                                            const std::string& label,
                                            const std::vector<double>& times = {1.5, 0.5});
// Outside the registry on a real table, one test point: the reference's (the table's own
// diagnosis) test point of its first row's light at its second distance and second angle (8 m
// and 10° on the article's protocol) read `times` its limit far in every recording, the limit
// the smallest departure the reference's placement test flags there (TwoSidedCritical of
// placement_alpha over the test points, times the median's placement law at that distance),
// named "LABEL + one test point read far, outside (1.5 × its limit)"; from 1 × on.
std::vector<WithheldCase> RealPointStepCases(const DiagnoseResult& reference,
                                             const std::string& label,
                                             const std::vector<double>& times,
                                             double placement_alpha);
// The name RealInjectionCases gives the case of `effect` at `times` its limit on table `label`.
std::string RealInjectionCaseName(const std::string& label, const std::string& effect,
                                  double times);
// The effects RealInjectionCases injects (each on its over-reading side).
const std::vector<std::string>& RealInjectionEffects();
// The names of every case RealInjectionCases may give on table `label` at those multiples
// (whichever the table's limits leave out).
std::vector<std::string> RealInjectionCaseNames(const std::string& label,
                                                const std::vector<double>& times);
// Whether a case name is one RealInjectionCases gives (any multiple).
bool IsRealInjectionCase(const std::string& name);
// The real rows with the case's effects applied by their physics, every row alike (or those of one
// light): a disparity offset δ reads each depth as Z' = f·B / (f·B / Z + δ) (fb = f·B in px·m): the
// median maps to Z', the mean's departure from it and the spreads by dZ'/dZ = (Z'/Z)², the range by
// Z'/Z, the tilt's tangent (the plane fit's error on a panel facing the camera) by (Z'/Z)³ read far
// and Z'/Z read near; valid_pct and disparity-unit columns stay. A depth scale s reads every depth
// and the range 1 + s times, the tilt's tangent (1 + s)² times read far and as it was read near
// (cases_real.cpp, TiltFactor). The panel's extent (width, height), measured in panel_extract's
// window of the panel's known size on the measured plane: read far it stays, read near it shrinks
// with the panel's image, by Z'/Z (or 1 + s), the bound (MapRow). plane_std grows no further than a
// uniform spread over the panel's shorter side, s/√12, where the plane fit's smallest axis turns
// into the panel's plane (the row's measured extent, else `panel_side_m`). Throws
// std::invalid_argument for another effect, or an offset that sends a depth beyond infinity.
std::vector<records::PanelMetrics> InjectIntoRealTable(
    const std::vector<records::PanelMetrics>& real, const WithheldCase& c, double fb,
    double panel_side_m);

// The null suite: no effect, 2 % placement scatter (tables at seeds seed0 + i); with `unit`, on a
// user's design (WithheldCase::unit: one light, one preset, 32 rows), named "null unit i".
std::vector<WithheldCase> NullCases(int count, bool unit = false);
// The first table seed of suite seed S's null tables: 2000 + 20·(S − 1) on the article's design,
// 10⁹ + 20·(S − 1) on a user's, so that no two suite seeds share a null table (S + 1999 did: the
// 20 tables of seeds 1–5 were 24 tables, not 100). Case i's table stays at S + 999 + i.
std::uint64_t NullTableSeed(std::uint64_t suite_seed, bool unit);

// The table of a case: the protocol's cells (the unit's: one light, one preset), each test
// point placed off by its own range error, the injected effects simulated, the outside effect
// applied. Rows keep their nominal distance. seed: the truth's simulation and placements
// (must differ from the diagnosis' seeds).
std::vector<records::PanelMetrics> MakeCaseTable(const sim::SimParams& base,
                                                 const WithheldCase& c, std::uint64_t seed,
                                                 const SimulateOptions& options);
// The protocol a case's table is made on (the unit's: one light, one preset).
sim::ProtocolParams CaseProtocol(const sim::ProtocolParams& base, const WithheldCase& c);

struct CaseOutcome {
  WithheldCase truth;
  std::vector<std::string> selected;
  std::map<std::string, std::string> recovered;  // effect → "scenario: param value, ..."
  double max_rel_error = 0;          // over injected parameters and scenarios; NaN: none fitted
  double shrink_simulated_pct = NAN;  // NaN: not published
  std::string unexplained;           // the rows `unexplained` names (ids), or "-"
  bool has_unexplained = false;
  bool pass = false;
  std::string why;                   // every criterion not met ("" when it passes)
  std::string gap_json;              // what the diagnosis wrote (RunWithheldCases)
};

// Judges one diagnosis, given as the gap.json it wrote, against the case it was made from;
// rows: the table's rows (ids, test points).
// reference_json (on_real cases, and only those): the diagnosis of the real table as it was.
// What it selects is the table's: an effect it selects that was not injected is no wrong
// answer. An injected effect is read as what the injection moved: the fitted value less the
// reference's own fit of that effect, where it selects it, or, where it selects nothing, its
// fit alone (a law below the table's limit is still the table's: on the article the depth
// scale fits +3.1 % and an injected +15.2 % reads +18.4 %; beside a selection a law's fit alone
// also takes what a correlated kept law holds, and none is subtracted); a depth scale by
// ratio, (1 + s)/(1 + s₀) − 1; against one shared answer, the reference's mean over the
// scenarios (its per-scenario fits of a law it does not select scatter far beyond their mean:
// the article's offset +0.24 to −0.37 px). The shrink is
// the share of the injected part of the nested held-out gap that the selection, simulated,
// removes beyond what the reference's removes: 100 · ((B − S) − (B₀ − S₀)) / (B − B₀), B and S
// the nested baseline and simulated gaps over the cells both hold out, all in the injected
// table's units: the reference's z brought over cell by cell by the ratio of the outer folds'
// units (gap.json's cells[].nested), since an injection that widens the twins' noise and the
// placement scatter moves the unit too. A may_go_unseen case also passes when
// nothing beyond the reference's selection is selected and the limit the injected table's
// gap.json publishes (the report a user reads) in the injected direction reaches the injected
// size.
CaseOutcome JudgeCase(const std::string& gap_json, const WithheldCase& truth,
                      const std::vector<records::PanelMetrics>& rows,
                      const std::string& reference_json = "");

// Every case's table made at truth_seed + its index and diagnosed with `base` (tables of the
// same cells share one set of simulations). Throws std::invalid_argument for a case the
// registry refuses or a diagnosis that fails.
// only: the indices of the cases to run (all when empty); a case's seed stays its index's.
std::vector<CaseOutcome> RunWithheldCases(const sim::SimParams& base,
                                          const std::vector<WithheldCase>& cases,
                                          const DiagnoseParams& params, std::uint64_t truth_seed,
                                          const std::vector<int>& only = {});

// The real table diagnosed as it is (the reference, whose limits size the cases), then with
// each of its RealInjectionCases injected at `times` its limits (InjectIntoRealTable, f·B of
// base.sensor), one set of simulations for all; `only`: the names of the cases to run (all when
// empty).
std::vector<CaseOutcome> RunRealInjectionCases(const sim::SimParams& base,
                                               const std::vector<records::PanelMetrics>& real,
                                               const std::string& label,
                                               const DiagnoseParams& params,
                                               const std::vector<std::string>& only = {},
                                               const std::vector<double>& times = {1.5, 0.5});

// The cases as a Markdown table; each null suite summarized in one row when given (how many
// select nothing, and how many leave something `unexplained`: a false finding of the open world).
std::string FormatCases(const std::vector<CaseOutcome>& outcomes,
                        const std::vector<CaseOutcome>& nulls = {},
                        const std::vector<CaseOutcome>& unit_nulls = {});
// At least 19 of 20 (95 %) null tables select nothing.
bool NullSuitePasses(const std::vector<CaseOutcome>& nulls);

}  // namespace depthbias::gap
