#pragma once
// What a campaign cannot see. "Nothing selected" says little on its own: on a table whose
// placement scatter is 1.3 m at 16 m, a camera law worth half a metre there cannot earn its
// place. For every registered effect this finds the smallest size, each way from its absence,
// that the diagnosis would keep on this table, from the table's own noise, placement scatter,
// dispersion and gap. Two bars, the higher decides:
//
//  1. The fit's own test. With the effect at θ in the truth, the fit's deviance drops by
//       λ(θ) = zᵀz − zᵀN (NᵀN + Λ)⁻¹ Nᵀz,   z = L⁻¹ Δ(θ)                                 (1)
//     on average: Δ(θ) the effect's simulated departure from the base in every observation,
//     L⁻¹ the fits' whitening (replicate noise, the test point's placement scatter, φ; fit.h
//     (2)), N the whitened calibration directions of each scenario (J_σ, J_p; those the effect
//     duplicates left out, held at their configured values as a fit holding the effect holds
//     them) and Λ their prior precisions (fit.h (3)): the calibration takes what it can. The
//     test asks ΔBIC > 0, a drop beyond ln n for one parameter, so θ is found with chance P
//     where √λ(θ) ≥ √(ln n) + Φ⁻¹(P). Where the table already holds a selection, the effect
//     is fitted beside it, whose terms move too: N also holds the whitened directions of every
//     selected term but the effect's own (each group's continuous axes, at its fitted values,
//     without a prior). An effect the selection can stand for is then seen only as far as it
//     departs from what the selection can take (a depth scale beside a kept offset).
//  2. The share of the gap an effect must remove to be kept, read as the keep rule reads it
//     (DiagnoseParams: min_effect_shrink_pct and min_own_shrink_pct, p, or in the metrics moved
//     min_moved_shrink_pct and min_own_moved_shrink_pct, q). Its gain in the gap's own units
//     over fold f's held-out observations of metric k, γ_fk(θ) = Σ (Δ(θ) / √(σ² + τ²))²,
//     against that fold's calibrated base G_fk (Σz², the outer folds' as the keep rule reads
//     them) once the effect is there. In the whole gap, s_f = γ_f / (G_f + γ_f) (sums over k);
//     in the metrics it moves, each weighing by γ_fk (MovedShare, diagnose.h),
//       m_f = Σ_k γ_fk² / Σ_k γ_fk (G_fk + γ_fk).
//     It passes where, by either reading, the mean over the folds reaches its own floor and,
//     when no other kept effect carries the selection's part, the same pooled over the folds
//     (γ, G summed) reaches the selection's. On a table with a large unexplained gap only a
//     large effect is kept; a gap in metrics it leaves alone raises only the whole reading's
//     bar. This holds for the mean gain; the draws of a table scatter about it.
//
// The selection also asks the outer folds' agreement and each effect's own share, so these are
// lower bounds of what the whole diagnosis needs (docs/gap/cases.md compares them with what the
// withheld suite found).
//
// The size is read along the axis that turns the effect on (its neutral value: an offset of 0,
// a gain of 1, a width of 0), the other axis of a two-axis effect at the node nearest its
// reference size; a discrete axis gives the first node that passes.

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "gap/fit.h"
#include "gap/json.h"

namespace depthbias::gap {

struct DetectionLimit {
  std::string effect;
  std::string param;         // the axis that turns the effect on
  double neutral = NAN;      // its value where the effect is absent
  bool discrete = false;     // a discrete axis: sizes are its nodes
  int frozen = 0;            // calibration components the effect duplicates (GapModel::Absorbs)
  std::string other;         // the other axis of a two-axis effect, or ""
  double other_value = NAN;  // where it is held: its node nearest its reference size
  // [0] below the neutral value, [1] above it; NaN where no size inside the simulated grid
  // passes. size: the higher bar of the two; by_test, by_share: each bar alone.
  std::array<double, 2> size{NAN, NAN};
  std::array<double, 2> by_test{NAN, NAN};
  std::array<double, 2> by_share{NAN, NAN};
  std::array<bool, 2> searched{false, false};  // the grid extends that way from the neutral
  // The median bias [m] `size` adds at the table's farthest distance (mean over its
  // recordings): what a camera of this law would read, that the campaign would miss. Where no
  // size passes (size NaN), at the grid's end: the camera could be at least that far off.
  std::array<double, 2> far_m{NAN, NAN};
};

struct LimitSettings {
  double power = 0.8;      // chance of finding an effect of the test's limit
  double min_share = 0.1;      // pooled share of the gap the selection must remove
  double min_own_share = 0.1;  // each fold's share an effect must remove, on average
  // or both of these, read in the metrics the effect moves
  double min_moved_share = 0.2;
  double min_own_moved_share = 0.3;
  // The outer folds: each cell's fold and each fold's calibrated Σz² on its held-out cells,
  // per compared metric (G_f,k). Empty: bar 2 not applied.
  std::vector<int> fold;
  std::vector<std::vector<double>> fold_gap_sq;
  bool pooled = true;      // the pooled share too (false: another kept effect carries it)
};

struct DetectionLimits {
  LimitSettings settings;
  double z_needed = 0;        // √(ln n) + Φ⁻¹(power)
  int observations = 0;       // n
  double far_distance_m = 0;  // the farthest distance of the table
  std::vector<DetectionLimit> effects;  // one per candidate, in the candidates' order
};

// Over the valid observations of the marked cells, at the model's dispersion and placement;
// beside `selection`'s terms when given (null or empty: beside the calibration alone).
DetectionLimits FindDetectionLimits(const GapModel& model, const std::vector<char>& cells,
                                    const LimitSettings& settings = {},
                                    const ModelFit* selection = nullptr);

// gap.json's "detection_limits" object.
void LimitsJson(records::JsonWriter& w, const DetectionLimits& l);

}  // namespace depthbias::gap
