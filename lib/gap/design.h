#pragma once
// The real table as the gap diagnostic sees it: its usable rows as simulator cells (distance,
// angle, preset, light, emitter), their scenarios (light × preset), the emitter on/off pairs of
// one test point (the replicates the noise is measured from), the metrics compared, and the
// held-out folds.

#include <array>
#include <string>
#include <vector>

#include "records/panel_metrics.h"
#include "sim/scene.h"
#include "sim/sensor.h"

namespace depthbias::gap {

// The compared metrics, each on a scale where real − sim means the same everywhere: depths in
// metres, logs for the spreads (they span a decade), points for valid_pct.
enum Metric {
  kMedianBias,       // median_m − distance_m [m]
  kMeanMinusMedian,  // mean_m − median_m [m]
  kPlaneStd,         // log plane_std_m
  kValidPct,         // valid_pct [points]
  kTemporalStd,      // log temporal_std_m
  kNormalTilt,       // normal_tilt_deg [deg]
  kPanelWidth,       // panel_width_m [m]
  kNumMetrics
};

struct MetricInfo {
  const char* name;       // e.g. "median_bias_m"
  const char* unit;       // "m", "log", "points", "deg"
  const char* meaning;
  // Noise model: scale · (Z / 10 m)^noise_exponent, Z the panel's depth. Disparity noise gives
  // depth errors ∝ Z² (σ_Z = Z²·σ_d/(f·B)); an extent in pixels ∝ Z.
  double noise_exponent;
  // The placement scatter's shape in Z for metrics other than the median (whose law is
  // a + b·D, placement.h): scale · (Z / 10 m)^placement_exponent.
  double placement_exponent;
  double noise_floor;  // smallest noise scale accepted (in the metric's unit, at Z = 10 m)
  bool core;           // the article's four: always compared
  // Quantization the replicates cannot show (two recordings of one panel mostly read the same
  // quantized median) but a model between grid nodes does: its RMS q/√12 is added to the noise
  // in quadrature. kDisparityStep: q = Z²·step/(f·B), one subpixel step of depth; kPixel: the
  // extent's two ends each quantized to a pixel footprint Z/f; kRelativeStep: q/T in the log of
  // a spread T of depths on that grid (a median over pixels of per-pixel spreads jumps between
  // the few values a spread of a handful of quantized depths can take).
  enum Quantum { kNone, kDisparityStep, kPixel, kRelativeStep } quantum;
  // Decided by the region's window: it moves by steps as pixels enter or leave the window, so
  // every simulation is a fresh draw of those steps (a candidate's surface is smoothed along
  // its parameters in these metrics, smooth.h).
  bool window = false;
  // A window metric whose steps a range law's surface reads averaged over placement
  // (smooth.h: AverageOverPlacement); not the plane's spread, which follows the depth itself.
  bool placement_average = false;
};
const MetricInfo& InfoOf(int metric);
// The metric of a row, transformed; NaN where the row does not have it.
double MetricValue(const records::PanelMetrics& row, int metric);
// Noise shape (Z / 10 m)^exponent of a metric at depth Z.
double NoiseShape(int metric, double depth_m);
// Placement scatter shape (Z / 10 m)^placement_exponent of a metric at depth Z.
double PlacementShape(int metric, double depth_m);
// RMS quantization of a metric at depth Z with focal f [px], baseline B [m], subpixel step [px];
// value: the metric's (transformed) value, for kRelativeStep.
double QuantizationRms(int metric, double depth_m, double focal_px, double baseline_m,
                       double step_px, double value);

struct Design {
  std::vector<sim::Cell> cells;            // one per usable row, in the table's order
  std::vector<int> row;                    // each cell's row in the input table (0-based)
  std::vector<std::string> bag;            // each cell's row id
  std::vector<std::string> scenario_names; // "daylight/HA", in first-seen order
  std::vector<int> scenario;               // each cell's scenario
  std::vector<std::string> light_names;    // "daylight", in first-seen order
  std::vector<int> scenario_light;         // each scenario's light
  std::vector<int> metrics;                // compared metrics (Metric values)
  std::vector<double> real;                // [cell·K + k], K = metrics.size(); NaN: missing
  std::vector<std::array<int, 2>> pairs;   // emitter on and off cells of one test point
  std::vector<std::string> skipped;        // rows left out and why ("row 5 (id): reason")

  int num_cells() const { return static_cast<int>(cells.size()); }
  int num_metrics() const { return static_cast<int>(metrics.size()); }
  int num_scenarios() const { return static_cast<int>(scenario_names.size()); }
  int num_lights() const { return static_cast<int>(light_names.size()); }
};

// The five factors of a table's cells.
enum class Factor { kLight, kDistance, kAngle, kPreset, kEmitter };

// Each cell's level of a factor, 0 … L − 1 in the order of the levels' text (a distance or
// angle as std::to_string gives it, "on" / "off"); L into *count when given.
std::vector<int> FactorLevels(const Design& design, Factor factor, int* count = nullptr);

// What a row must be for the simulator to stand for it, from the sensor (DesignRulesOf). A row
// outside is left out of the design and listed with its reason (ScreenRows): never simulated
// with a guessed noise, never silently dropped.
struct DesignRules {
  // Scenarios "light/preset" the sensor lists (its calibrated noise and holes); empty: the
  // sensor lists none, and every scenario has its fallback.
  std::vector<std::string> scenarios;
  bool d455_presets_only = true;   // a preset must be one of the D455's (camera/presets.h)
  double min_distance_m = 0.4;     // the sensor's range: a panel nearer or farther reads nothing
  double max_distance_m = 25.0;
  double max_left_deg = 45.0;      // the panel's centre inside the horizontal field of view
  double max_right_deg = 45.0;
  // Rows a table may have: each distinct cell is about a hundred simulations (about 0.3 s of
  // CPU per cell on this machine), so 1024 rows are minutes, and a bigger table is refused.
  int max_rows = kMaxTableRows;

  static constexpr int kMaxTableRows = 1024;
  bool IsValid(std::string* why) const;
};
DesignRules DesignRulesOf(const sim::SensorParams& sensor);

// Marks every ok row the rules leave out with status "left_out" and the reason in its message;
// returns how many. BuildDesign then lists them in Design::skipped.
int ScreenRows(const DesignRules& rules, std::vector<records::PanelMetrics>* rows);

// Rows with a status other than "ok" are skipped (listed in design->skipped). A usable row needs
// numbers in distance_m, angle_deg, mean_m, median_m, plane_std_m and valid_pct, emitter on or
// off, and a light and a preset. The extra metrics are compared when the table has them in at
// least 90 % of its usable rows. Returns false with a one-line reason naming the row otherwise,
// when no row is usable (the reason then says why the first was left out), or when the table
// has more than DesignRules::kMaxTableRows rows.
bool BuildDesign(const std::vector<records::PanelMetrics>& rows, Design* design,
                 std::string* why);

// The cells of `design` marked in `cells`, scenarios and metrics kept.
Design Subset(const Design& design, const std::vector<char>& cells);

// Which cells a cross-validation holds out together.
enum class HoldoutKind { kDistance, kPoint, kLight, kPreset };
struct Holdout {
  HoldoutKind kind = HoldoutKind::kDistance;
  std::string value;  // the light or preset held out (kLight, kPreset)
};
// "distance", "point", "light=V", "preset=V".
bool ParseHoldout(const std::string& text, Holdout* holdout, std::string* why);
std::string HoldoutName(const Holdout& holdout);

// Fold of every cell (−1: never held out) and the number of folds: one per distance or test
// point (distance, angle: its emitter rows leave together), or the one fold of the cells with
// light (preset) V. Returns false with a reason if a fold would leave nothing to fit on, or
// nothing is held out.
bool Folds(const Design& design, const Holdout& holdout, std::vector<int>* fold, int* num_folds,
           std::string* why);

}  // namespace depthbias::gap
