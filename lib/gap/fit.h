#pragma once
// The fits of the diagnosis: effects (each at values interpolated between its simulated grid
// nodes) added to the base simulation, jointly with the calibration's nuisance parameters,
// solved with Ceres.
//
// For an observation (cell c, compared metric k) with real value y and base simulation b:
//   μ = b + Σ_terms Δ_term(θ_term,g(c)) + J_σ·n_σ,s(c) + J_p·n_p,s(c)  [+ (1a)]          (1)
//   r = L⁻¹ (y − μ),   L Lᵀ = φ_k · diag(σ²) + ψ_k · τ_k(D_t)² · l lᵀ                      (2)
//   and between metrics k ≠ k' of one test point √(ψ_k ψ_k') · τ_k τ_k' · g_k g_k' · l l'ᵀ
// Δ_term is the term's simulated departure from the base, interpolated between grid nodes; g(c)
// the term's group of the cell (one shared group, the cell's light or its scenario: Scope); n_s
// the scenario's calibration moves (Δ log σ_d, Δ logit p), linear through the Jacobian J
// simulated at the base;
// σ the replicate noise (noise.h), τ the placement scatter of the test point t the recordings
// share (placement.h: one random effect per test point and metric, so the recordings of one
// placement count as one piece of evidence, not four), l its loadings (1 but for a spread, whose
// recordings take the displacement by their own scenario's sensitivity: tau_cell), and φ_k,
// g_k the share of the metric's scatter that is the panel's displacement the median reads
// (PlacementEstimate::Shared: FitSettings::joint_placement), ψ_k the metric's dispersions
// (how much wider than the replicate noise the recordings of one test point spread about their
// mean, and how much wider than the placement law the test points' means spread, each ≥ 1:
// select.h, Dispersion); the residuals are whitened block by block (test point × metric, the
// metrics with a share g ≠ 0 in one block per test point). Effects of several terms add (in the
// metrics' own scales).
// Ceres minimizes the deviance
//   D = Σ 2ρ(r) + Σ_s (n_σ,s/τ_σ)² + (n_p,s/τ_p)²                                     (3)
// with ρ Huber's loss at k (plain squares for k ≤ 0): the calibration may move, at a cost set by
// its prior widths τ, but no further than the data ask.

#include <array>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "gap/design.h"
#include "gap/noise.h"
#include "gap/placement.h"
#include "gap/simulations.h"

namespace depthbias::gap {

struct FitSettings {
  double huber_k = 3.0;         // robust loss threshold [noise units]; <= 0: plain squares
  double tau_log_sigma = 0.15;  // prior width of each scenario's Δ log σ_d
  double tau_logit_p = 0.3;     // prior width of each scenario's Δ logit p
  int max_iterations = 50;
  // Effects that move the window through the measured depth read it at their joint depth (1a);
  // false: each one's window departures add, as every other metric's (the default: docs/gap/
  // cases.md, The window at the joint depth). A selection read beside a named effect is read
  // with it (JointWindow, diagnose.cpp).
  bool joint_window = false;
  // One displacement read in every metric it moves: a test point's median and spreads share the
  // panel's displacement along its line of sight (PlacementEstimate::Shared), so that a spread
  // that does not follow its median's departure is read against what is left of its scatter,
  // not against all of it (2). false (the default): each metric's scatter its own; the rule on
  // a range law and the spreads reads the table with it (select.h, MedianWithoutSpreads).
  bool joint_placement = false;

  bool IsValid(std::string* why) const;
};

// Which cells share an effect's parameters: every cell (one group), the cells of one light
// (sunlight that heats the unit or floods the sensor acts in both presets alike), or of one
// scenario (light × preset).
enum class Scope { kShared, kPerLight, kPerScenario };
const char* ScopeName(Scope scope);  // "shared", "per_light", "per_scenario"
// The scope's groups in a design, the group of a scenario, and a group's name ("all",
// "daylight", "daylight/HA").
int ScopeGroups(const Design& design, Scope scope);
int ScopeGroupOf(const Design& design, Scope scope, int scenario);
std::string ScopeGroupName(const Design& design, Scope scope, int group);
// The scope applies: more than one group, and (per light) fewer lights than scenarios.
bool ScopeApplies(const Design& design, Scope scope);

// One effect in a model: a candidate (index into the simulations' surfaces), its parameters
// shared by every cell or one set per group of its scope, and the node of each discrete axis.
struct Term {
  int candidate = 0;
  Scope scope = Scope::kShared;
  // [group][axis]: the node index of a discrete axis, −1 for a continuous one; one row serves
  // every group.
  std::vector<std::vector<int>> discrete_node;

  int Discrete(int group, int axis) const {
    if (discrete_node.empty()) return -1;
    const auto& row = discrete_node[discrete_node.size() == 1 ? 0 : group];
    return axis < static_cast<int>(row.size()) ? row[axis] : -1;
  }
};

struct TermFit {
  Term term;
  std::vector<std::vector<double>> values;  // [group][axis], natural units
  // 95 % interval [group][axis]: a continuous axis ± 1.96 times the wider of the fit's own
  // standard error and the sandwich's over the test points (robust_covariance.h); a discrete
  // axis its value, or where `profiled`, the hull of the nodes its profile over the nodes keeps
  // (the diagnosis's selected terms).
  std::vector<std::vector<double>> ci_lo;
  std::vector<std::vector<double>> ci_hi;
  bool profiled = false;
  // The value sits on the grid's edge short of the parameter's own bound (where the data would
  // take it further than was simulated: not determined). At a bound of the registry's (a gain
  // of 0, a weight of 1) the value is the bound: determined, its interval clipped to it.
  std::vector<std::vector<char>> at_bound;
  std::vector<char> group_used;             // the group had cells in the fit (else: mean)
};

struct ModelFit {
  bool success = false;
  std::string message;
  std::vector<TermFit> terms;
  std::vector<std::array<double, 2>> nuisance;     // per scenario: Δ log σ_d, Δ logit p
  std::vector<std::array<double, 2>> nuisance_sd;  // their standard errors
  double data_deviance = 0;  // Σ 2ρ(r) over the fitted observations
  double prior = 0;          // Σ (n/τ)²
  int num_obs = 0;           // observations fitted
  int num_params = 0;        // effect parameters (the BIC's k)
  std::string report;        // Ceres' brief report

  double Deviance() const { return data_deviance + prior; }
};

// Huber's loss as a residual: r̃ = r for |r| ≤ k, sign(r)·√(2k|r| − k²) beyond, so that
// r̃² = 2ρ(r); dr̃/dr = 1 inside, k/|r̃| beyond.
inline double Robust(double r, double k, double* d) {
  if (k <= 0 || std::fabs(r) <= k) {
    *d = 1;
    return r;
  }
  const double rt = std::copysign(std::sqrt(2 * k * std::fabs(r) - k * k), r);
  *d = k / std::fabs(rt);
  return rt;
}

class GapModel {
 public:
  // The design, simulations, noise and placement must outlive the model; without a placement
  // estimate (nullptr or empty) every recording is its own block (τ = 0).
  GapModel(const Design& design, const Simulations& sims, const NoiseEstimate& noise,
           const FitSettings& settings, const PlacementEstimate* placement = nullptr);

  const Design& design() const { return design_; }
  const Simulations& sims() const { return sims_; }
  const FitSettings& settings() const { return settings_; }
  int num_obs() const { return static_cast<int>(y_.size()); }
  int num_metrics() const { return design_.num_metrics(); }
  bool valid(size_t obs) const { return valid_[obs] != 0; }
  double y(size_t obs) const { return y_[obs]; }
  // The unit of z: replicate noise and placement scatter, √(σ² + τ²).
  double noise(size_t obs) const { return total_[obs]; }
  double replicate_noise(size_t obs) const { return sigma_[obs]; }
  double placement(size_t obs) const { return total_[obs] > sigma_[obs] ?
      std::sqrt(total_[obs] * total_[obs] - sigma_[obs] * sigma_[obs]) : 0.0; }
  double weight(size_t obs) const;  // 1 / √(φ_k·σ² + ψ_k·τ²)

  // The observations grouped in blocks (test point × metric), each block's whitening L⁻¹ of
  // (2) row-major; obs sorted block by block, starts[b] the first of block b (and the end).
  struct Whitening {
    std::vector<size_t> obs;
    std::vector<int> starts;
    std::vector<std::vector<double>> linv;
  };
  Whitening Whiten(const std::vector<size_t>& obs) const;
  // The dispersions, per compared metric φ_k (the replicate noise's) then ψ_k (the placement
  // scatter's): 2 × metrics values; given one per metric, both take it.
  const std::vector<double>& dispersion() const { return phi_; }
  void SetDispersion(const std::vector<double>& phi);
  // A candidate's surface as the fits read it: the simulations' own, a range law's window
  // metrics averaged over the placement scatter's law (smooth.h: AverageOverPlacement).
  const Surface& surface(int candidate) const {
    return own_of_[candidate] < 0 ? sims_.surfaces[candidate] : own_[own_of_[candidate]];
  }

  // The calibration components a candidate duplicates (bit 0: σ_d, bit 1: hole probability):
  // its signature lies along them (disparity_noise_gain is a σ_d change, invalidation_gain one
  // of the hole odds). A model holding such a term keeps those components at the configured
  // values: moving both would leave a free second-order difference that fits noise.
  void SetAbsorbs(int candidate, int mask) { absorbs_[candidate] = mask; }
  int Absorbs(int candidate) const { return absorbs_[candidate]; }
  int Frozen(const std::vector<Term>& terms) const;
  // The same model with a candidate's departures in the spreads (mean − median, plane_std,
  // temporal_std) held at the base, every other metric's kept: its law without what it does to
  // the spreads (select.h, MedianWithoutSpreads).
  GapModel WithoutSpreads(int candidate) const;
  // The same model with FitSettings::joint_placement on.
  GapModel JointPlacement() const;
  // The same model with FitSettings::joint_window on (1a).
  GapModel JointWindow() const;
  // The same model read against y − c: a part of the departures the terms' sum does not carry,
  // found by simulating the terms together (select.h, SimulatedBeside). c NaN: y as it is.
  GapModel Shifted(const std::vector<double>& c) const;

  int NumGroups(const Term& term) const;
  int Group(const Term& term, int cell) const;
  // Coordinates of an axis value (its log for a log-scale axis) and back.
  double ToCoord(int candidate, int axis, double value) const;
  double FromCoord(int candidate, int axis, double coord) const;
  const std::vector<double>& NodeCoords(int candidate, int axis) const {
    return coords_[candidate][axis];
  }
  // The term's departure from the base at coordinates u (one per axis) for one observation.
  double Delta(const Term& term, const double* u, size_t obs) const;
  // The window's one response to the measured depth (1a). A term that moves the window through
  // the measured depth (Candidate::moves_window) carries in the metrics the window decides (its
  // own, MetricInfo::window, and the valid share, which falls once the window outgrows the
  // panel) the response to its own median departure M_t; where two or more such terms act, the
  // window follows their sum M = Σ M_t, not each alone. With H the disparity offset's departure
  // in that metric as a function of its median departure (its surface's nodes, the cell's own),
  // the terms' departures take H(M) − Σ H(M_t) more: nothing for one term, and for an offset
  // beside a drift, the drift's own part plus H at their joint depth. (Simulated at seed 1001,
  // the valid share at 16 m: −0.004 points for an offset of 0.15 px alone, −0.006 for a drift of
  // 0.6 px/s alone, −1.72 for both; −1.94 for an offset of 0.25 px, which reads as near.)
  // Whether the terms take it: FitSettings::joint_window, two or more of them move the window,
  // an offset surface and the median.
  bool SharesWindow(const std::vector<Term>& terms) const;
  // H(M) − Σ H(M_t) at observation obs, u[t] term t's coordinates at obs's group; 0 but in the
  // metrics the window decides.
  double WindowInteraction(const std::vector<Term>& terms, const double* const* u,
                           size_t obs) const;
  // Prediction μ (1) of every observation under a fit (every cell, fitted or not).
  std::vector<double> Predict(const ModelFit& fit) const;
  // Σ 2ρ(r) over the valid observations of the cells marked in `cells`.
  // With `per_unit`, also each independent unit's part, keyed by unit: a test point (the
  // placement its recordings share), or a recording without one (key −1 − cell).
  double DataDeviance(const std::vector<double>& mu, const std::vector<char>& cells,
                      std::map<long long, double>* per_unit = nullptr) const;
  // The independent unit of an observation: its test point (≥ 0), or its recording alone
  // (−1 − cell) where there is no placement estimate.
  long long Unit(size_t obs) const {
    return block_[obs] >= 0 ? block_[obs] : -1 - static_cast<long long>(obs / num_metrics());
  }

 private:
  const Design& design_;
  const Simulations& sims_;
  FitSettings settings_;
  std::vector<double> y_, sigma_, total_, phi_;
  std::vector<int> block_;  // [obs] its test point (−1: a block of its own)
  std::vector<double> shared_;  // [obs] g of (2): its scatter's share the displacement is
  std::vector<char> valid_;
  std::vector<std::vector<std::vector<double>>> coords_;  // [candidate][axis][node]
  std::vector<int> absorbs_;                               // [candidate]
  std::vector<Surface> own_;  // the surfaces averaged over placement
  std::vector<int> own_of_;   // [candidate] its index in own_, −1: the simulations'
  int median_k_ = -1;         // the median's position among the compared metrics
  // [obs] of a metric the window decides: H's nodes, median departures ascending, and the
  // metric's departures at them (WindowInteraction); empty without an offset surface.
  std::vector<std::vector<double>> window_m_, window_h_;
  double WindowResponse(size_t obs, double m) const;
};

// Fits the terms (with their discrete nodes fixed) and the calibration on the marked cells,
// starting from `start` (a fit of the same terms; else each term from its best grid node).
ModelFit FitTerms(const GapModel& model, const std::vector<Term>& terms,
                  const std::vector<char>& train, const ModelFit* start = nullptr);

// The terms of `fit` refitted on the marked cells with `beside` added last, each term starting
// from its own values (the calibration components `beside` duplicates held: Frozen).
ModelFit FitBeside(const GapModel& model, const ModelFit& fit, const TermFit& beside,
                   const std::vector<char>& train);

// One candidate alone: every grid node is tried (the calibration solved in closed form, plain
// squares), and FitTerms refines from the best starts: the lowest local minima of that profile
// (shared), or each group's best node and the shared fit's values when given (per light or
// scenario). With a discrete axis (a width), every width is tried too (its best node a start),
// and the fits (Huber's loss, as always) are told apart by Tukey's biweight at 4.5 over the
// whitened residuals, whatever huber_k is; per light or scenario, each group's width is chosen
// on its own cells (fit_candidate.cpp, WidthDeviance: a test point whose window metric sits in
// its other mode under placement counts as one miss). Without one, by the lowest deviance.
ModelFit FitCandidate(const GapModel& model, int candidate, Scope scope,
                      const std::vector<char>& train, const ModelFit* shared = nullptr);

// The 95 % interval of each discrete axis of the fitted terms (a width, fitted at one node): the
// hull of the nodes whose refit raises the deviance by at most χ²₁(0.95) = 3.84 over the lowest
// refit of all the nodes (a profile likelihood over the nodes, conditional on the other widths;
// a continuous axis's interval comes from the fit's curvature). At each node the continuous
// parameters and the calibration are refitted, started from the fit's values and from the axes'
// neutral values (their reference where they have none), the lower deviance kept; the other
// terms' and groups' widths stay. The fitted node is always inside. Marks the terms `profiled`;
// a group without cells gets no interval (NaN). Nothing is refitted without a discrete axis.
void ProfileDiscreteAxes(const GapModel& model, const std::vector<char>& cells, ModelFit* fit);

// Held-out predictions: each fold's cells predicted by the terms refitted on the other cells
// (single candidates by FitCandidate, so their discrete nodes are chosen without the fold;
// combinations by FitTerms from `full`). Cells never held out get NaN.
struct HeldOut {
  std::vector<double> mu;      // [obs]
  std::vector<char> cells;     // held out at least once
  double data_deviance = 0;    // Σ 2ρ(r) over the held-out observations
  bool success = true;
  std::string message;
};
// Only cells marked in `use` (all when empty) are fitted or held out.
HeldOut CrossValidate(const GapModel& model, const std::vector<Term>& terms,
                      const std::vector<int>& fold, int num_folds, const ModelFit& full,
                      const std::vector<char>& use = {});

}  // namespace depthbias::gap
