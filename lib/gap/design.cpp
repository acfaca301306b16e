#include "gap/design.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "camera/presets.h"

namespace depthbias::gap {
namespace {

const MetricInfo kMetrics[kNumMetrics] = {
    {"median_bias_m", "m", "median depth − nominal distance", 2.0, 2.0, 0.002, true,
     MetricInfo::kDisparityStep},
    {"mean_minus_median_m", "m", "mean − median depth (far tail of the region's samples)", 2.0,
     2.0, 0.002, true, MetricInfo::kDisparityStep, true, true},
    // A statistic over the N ∝ Z⁻² pixels of a panel of fixed size: the log of a spread and a
    // share of valid pixels (binomial) both scatter as 1/√N ∝ Z between recordings (emitter
    // twins of the withheld suite's tables without effect, 4 → 16 m: log plane_std 0.0040 →
    // 0.0175, valid_pct 0.12 → 0.51 points). A panel placed 2 % off moves the log spread by the
    // same 0.04 at every distance (plane_std ∝ Z²): its placement scatter is flat in Z.
    // Beyond 12 m the spread follows the window's whole pixels too (simulate --metrics-only,
    // daylight HA at 16 m and 0°: 5 % above its Z² law from a 0.1 px offset on, where the region
    // grows from 39 to 41 pixels a side; within 1 % at 4–12 m): a window metric, smoothed but
    // not averaged over placement (smooth.h).
    {"log_plane_std", "log", "log of plane_std_m (spread about the panel's plane)", 1.0, 0.0,
     0.005, true, MetricInfo::kNone, true},
    {"valid_pct", "points", "share of valid samples in the region", 1.0, 0.0, 0.1, true,
     MetricInfo::kNone},
    {"log_temporal_std", "log", "log of temporal_std_m (per-pixel spread over time)", 0.0, 0.0,
     0.005, false, MetricInfo::kRelativeStep},
    // The fitted normal's angle error: σ_Z ∝ Z² over a panel of fixed size seen by N ∝ Z⁻²
    // pixels, σ_tilt ∝ σ_Z / (size·√N) ∝ Z³ (and a tilt's magnitude is biased up by as much).
    {"normal_tilt_deg", "deg", "angle of the fitted panel normal to the optical axis", 3.0, 3.0,
     0.05, false, MetricInfo::kNone, true, true},
    {"panel_width_m", "m", "width of the panel found", 1.0, 1.0, 0.002, false,
     MetricInfo::kPixel, true, true},
};

std::string Where(const records::PanelMetrics& row, size_t index) {
  return "row " + std::to_string(index + 1) + " (" + row.bag + ")";
}

double Log(double v) { return std::isfinite(v) && v > 0 ? std::log(v) : NAN; }

std::string Num(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

std::string Joined(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

// Why the rules leave a row out ("" if they do not).
std::string LeftOutBecause(const DesignRules& rules, const records::PanelMetrics& r) {
  double option = 0;
  if (rules.d455_presets_only && !camera::PresetOptionValue(r.preset, &option)) {
    std::vector<std::string> names;
    for (int k = 0; k <= 6; ++k) names.push_back(camera::PresetName(k));
    return "preset '" + r.preset + "' is not a D455 preset (" + Joined(names) + ")";
  }
  const std::string scenario = r.light + "/" + r.preset;
  if (!rules.scenarios.empty() &&
      std::find(rules.scenarios.begin(), rules.scenarios.end(), scenario) ==
          rules.scenarios.end())
    return "light '" + r.light + "' with preset '" + r.preset +
           "' is not a scenario of the sensor (it lists " + Joined(rules.scenarios) +
           "): its noise would be a guess; calibrate it (simulate --calibrate-to)";
  if (std::isfinite(r.distance_m) &&
      (r.distance_m < rules.min_distance_m || r.distance_m > rules.max_distance_m))
    return "distance_m " + Num(r.distance_m) + " is outside the sensor's range (" +
           Num(rules.min_distance_m) + " to " + Num(rules.max_distance_m) + " m)";
  if (std::isfinite(r.angle_deg) &&
      (r.angle_deg > rules.max_right_deg || -r.angle_deg > rules.max_left_deg))
    return "angle_deg " + Num(r.angle_deg) +
           " puts the panel's centre outside the sensor's field of view (" +
           Num(-rules.max_left_deg) + " to " + Num(rules.max_right_deg) + " deg)";
  return "";
}

}  // namespace

const MetricInfo& InfoOf(int metric) { return kMetrics[metric]; }

double MetricValue(const records::PanelMetrics& r, int metric) {
  switch (metric) {
    case kMedianBias: return r.median_m - r.distance_m;
    case kMeanMinusMedian: return r.mean_m - r.median_m;
    case kPlaneStd: return Log(r.plane_std_m);
    case kValidPct: return r.valid_pct;
    case kTemporalStd: return Log(r.temporal_std_m);
    case kNormalTilt: return r.normal_tilt_deg;
    case kPanelWidth: return r.panel_width_m;
    default: return NAN;
  }
}

double NoiseShape(int metric, double depth_m) {
  return std::pow(std::max(depth_m, 0.1) / 10.0, kMetrics[metric].noise_exponent);
}

double PlacementShape(int metric, double depth_m) {
  return std::pow(std::max(depth_m, 0.1) / 10.0, kMetrics[metric].placement_exponent);
}

double QuantizationRms(int metric, double depth_m, double focal_px, double baseline_m,
                       double step_px, double value) {
  const double q = depth_m * depth_m * step_px / (focal_px * baseline_m);
  switch (kMetrics[metric].quantum) {
    case MetricInfo::kDisparityStep:
      return q / std::sqrt(12.0);
    case MetricInfo::kRelativeStep:
      return std::isfinite(value) ? q / std::exp(value) / std::sqrt(12.0) : 0.0;
    case MetricInfo::kPixel:
      return depth_m / focal_px * std::sqrt(2.0 / 12.0);
    default:
      return 0.0;
  }
}

bool DesignRules::IsValid(std::string* why) const {
  if (!(min_distance_m > 0 && max_distance_m > min_distance_m) || !(max_left_deg > 0) ||
      !(max_right_deg > 0) || max_left_deg >= 90 || max_right_deg >= 90 || max_rows < 1) {
    if (why)
      *why = "design rules: need 0 < min_distance_m < max_distance_m, field of view in (0, 90) "
             "deg each side, max_rows >= 1";
    return false;
  }
  return true;
}

DesignRules DesignRulesOf(const sim::SensorParams& sensor) {
  DesignRules rules;
  for (const sim::ScenarioParams& s : sensor.scenarios)
    rules.scenarios.push_back(s.light + "/" + s.preset);
  rules.min_distance_m = sensor.min_depth_m;
  rules.max_distance_m = sensor.max_depth_m;
  const camera::Intrinsics& k = sensor.intrinsics;
  // Pixel centres at integer coordinates: the image spans [−0.5, width − 0.5].
  rules.max_left_deg = std::atan((k.ppx + 0.5) / k.fx) * 180 / M_PI;
  rules.max_right_deg = std::atan((k.width - 0.5 - k.ppx) / k.fx) * 180 / M_PI;
  return rules;
}

int ScreenRows(const DesignRules& rules, std::vector<records::PanelMetrics>* rows) {
  int left_out = 0;
  for (records::PanelMetrics& r : *rows) {
    if (!r.ok()) continue;
    const std::string because = LeftOutBecause(rules, r);
    if (because.empty()) continue;
    r.status = "left_out";
    r.message = because;
    ++left_out;
  }
  return left_out;
}

bool BuildDesign(const std::vector<records::PanelMetrics>& rows, Design* design,
                 std::string* why) {
  if (rows.size() > static_cast<size_t>(DesignRules::kMaxTableRows)) {
    if (why)
      *why = "the table has " + std::to_string(rows.size()) + " rows, more than the " +
             std::to_string(DesignRules::kMaxTableRows) + " a diagnosis takes";
    return false;
  }
  Design d;
  std::vector<const records::PanelMetrics*> used;
  for (size_t i = 0; i < rows.size(); ++i) {
    const records::PanelMetrics& r = rows[i];
    if (!r.ok()) {
      d.skipped.push_back(Where(r, i) + ": " +
                          (r.status == "left_out" ? r.message
                                                  : "status " + r.status +
                                                        (r.message.empty() ? ""
                                                                           : " (" + r.message +
                                                                                 ")")));
      continue;
    }
    const std::pair<const char*, double> needed[] = {
        {"distance_m", r.distance_m}, {"angle_deg", r.angle_deg},     {"mean_m", r.mean_m},
        {"median_m", r.median_m},     {"plane_std_m", r.plane_std_m}, {"valid_pct", r.valid_pct}};
    for (const auto& [name, value] : needed) {
      if (!std::isfinite(value)) {
        if (why) *why = Where(r, i) + ": " + name + " is not a number";
        return false;
      }
    }
    if (!(r.distance_m > 0) || !(r.plane_std_m > 0) || r.valid_pct < 0 || r.valid_pct > 100 ||
        std::fabs(r.angle_deg) >= 80) {
      if (why)
        *why = Where(r, i) +
               ": needs distance_m > 0, plane_std_m > 0, valid_pct in [0, 100], |angle_deg| < 80";
      return false;
    }
    if (r.emitter != "on" && r.emitter != "off") {
      if (why) *why = Where(r, i) + ": emitter must be on or off, not '" + r.emitter + "'";
      return false;
    }
    if (r.light.empty() || r.preset.empty()) {
      if (why) *why = Where(r, i) + ": light and preset must not be empty";
      return false;
    }
    sim::Cell c;
    c.distance_m = r.distance_m;
    c.angle_deg = r.angle_deg;
    c.preset = r.preset;
    c.light = r.light;
    c.emitter_on = r.emitter == "on";
    c.name = sim::CellName(c);
    const std::string scenario = r.light + "/" + r.preset;
    auto it = std::find(d.scenario_names.begin(), d.scenario_names.end(), scenario);
    d.scenario.push_back(static_cast<int>(it - d.scenario_names.begin()));
    if (it == d.scenario_names.end()) {
      d.scenario_names.push_back(scenario);
      auto light = std::find(d.light_names.begin(), d.light_names.end(), r.light);
      d.scenario_light.push_back(static_cast<int>(light - d.light_names.begin()));
      if (light == d.light_names.end()) d.light_names.push_back(r.light);
    }
    d.cells.push_back(c);
    d.row.push_back(static_cast<int>(i));
    d.bag.push_back(r.bag);
    used.push_back(&r);
  }
  if (used.empty()) {
    if (why)
      *why = rows.empty()       ? "the table has no rows"
             : d.skipped.empty() ? "no row has status ok"
                                 : "no usable row: " + std::to_string(d.skipped.size()) +
                                       " left out, the first " + d.skipped.front();
    return false;
  }
  for (int m = 0; m < kNumMetrics; ++m) {
    int finite = 0;
    for (const auto* r : used) finite += std::isfinite(MetricValue(*r, m)) ? 1 : 0;
    if (kMetrics[m].core || finite >= 0.9 * static_cast<double>(used.size()))
      d.metrics.push_back(m);
  }
  const size_t k = d.metrics.size();
  d.real.assign(used.size() * k, NAN);
  for (size_t c = 0; c < used.size(); ++c)
    for (size_t j = 0; j < k; ++j) d.real[c * k + j] = MetricValue(*used[c], d.metrics[j]);

  // Replicates: the emitter on and off rows of one test point (first of each when repeated).
  std::map<std::string, std::array<int, 2>> points;
  for (int c = 0; c < d.num_cells(); ++c) {
    const sim::Cell& cell = d.cells[c];
    std::ostringstream key;
    key << cell.light << '|' << cell.preset << '|' << cell.distance_m << '|' << cell.angle_deg;
    auto& p = points.try_emplace(key.str(), std::array<int, 2>{-1, -1}).first->second;
    int& slot = p[cell.emitter_on ? 0 : 1];
    if (slot < 0) slot = c;
  }
  for (const auto& [key, p] : points)
    if (p[0] >= 0 && p[1] >= 0) d.pairs.push_back(p);
  *design = std::move(d);
  return true;
}

Design Subset(const Design& d, const std::vector<char>& cells) {
  Design s;
  s.scenario_names = d.scenario_names;
  s.light_names = d.light_names;
  s.scenario_light = d.scenario_light;
  s.metrics = d.metrics;
  const int kk = d.num_metrics();
  for (int c = 0; c < d.num_cells(); ++c) {
    if (!cells[c]) continue;
    s.cells.push_back(d.cells[c]);
    s.row.push_back(d.row[c]);
    s.bag.push_back(d.bag[c]);
    s.scenario.push_back(d.scenario[c]);
    for (int k = 0; k < kk; ++k) s.real.push_back(d.real[static_cast<size_t>(c) * kk + k]);
  }
  return s;
}

bool ParseHoldout(const std::string& text, Holdout* h, std::string* why) {
  Holdout out;
  if (text == "distance") {
    out.kind = HoldoutKind::kDistance;
  } else if (text == "point") {
    out.kind = HoldoutKind::kPoint;
  } else if (text.rfind("light=", 0) == 0 && text.size() > 6) {
    out.kind = HoldoutKind::kLight;
    out.value = text.substr(6);
  } else if (text.rfind("preset=", 0) == 0 && text.size() > 7) {
    out.kind = HoldoutKind::kPreset;
    out.value = text.substr(7);
  } else {
    if (why) *why = "holdout '" + text + "': use distance, point, light=V or preset=V";
    return false;
  }
  *h = out;
  return true;
}

std::string HoldoutName(const Holdout& h) {
  switch (h.kind) {
    case HoldoutKind::kDistance: return "distance";
    case HoldoutKind::kPoint: return "point";
    case HoldoutKind::kLight: return "light=" + h.value;
    case HoldoutKind::kPreset: return "preset=" + h.value;
  }
  return "";
}

bool Folds(const Design& d, const Holdout& h, std::vector<int>* fold, int* num_folds,
           std::string* why) {
  fold->assign(d.cells.size(), -1);
  if (h.kind == HoldoutKind::kLight || h.kind == HoldoutKind::kPreset) {
    int held = 0;
    for (size_t c = 0; c < d.cells.size(); ++c) {
      const std::string& v =
          h.kind == HoldoutKind::kLight ? d.cells[c].light : d.cells[c].preset;
      if (v == h.value) {
        (*fold)[c] = 0;
        ++held;
      }
    }
    *num_folds = 1;
    if (held == 0 || held == static_cast<int>(d.cells.size())) {
      if (why)
        *why = "holdout " + HoldoutName(h) +
               (held == 0 ? ": no row has that value" : ": every row has that value");
      return false;
    }
    return true;
  }
  std::map<std::pair<double, double>, int> keys;
  for (const sim::Cell& c : d.cells)
    keys.emplace(std::make_pair(c.distance_m,
                                h.kind == HoldoutKind::kPoint ? c.angle_deg : 0.0),
                 0);
  int i = 0;
  for (auto& [key, id] : keys) id = i++;
  *num_folds = i;
  if (i < 2) {
    if (why) *why = "holdout " + HoldoutName(h) + ": the table has only one " + HoldoutName(h);
    return false;
  }
  for (size_t c = 0; c < d.cells.size(); ++c)
    (*fold)[c] = keys.at(std::make_pair(
        d.cells[c].distance_m, h.kind == HoldoutKind::kPoint ? d.cells[c].angle_deg : 0.0));
  return true;
}

std::vector<int> FactorLevels(const Design& d, Factor factor, int* count) {
  std::map<std::string, int> ids;
  std::vector<std::string> key(d.cells.size());
  for (size_t c = 0; c < d.cells.size(); ++c) {
    const sim::Cell& cell = d.cells[c];
    switch (factor) {
      case Factor::kLight: key[c] = cell.light; break;
      case Factor::kDistance: key[c] = std::to_string(cell.distance_m); break;
      case Factor::kAngle: key[c] = std::to_string(cell.angle_deg); break;
      case Factor::kPreset: key[c] = cell.preset; break;
      case Factor::kEmitter: key[c] = cell.emitter_on ? "on" : "off"; break;
    }
    ids.emplace(key[c], 0);
  }
  int i = 0;
  for (auto& [k, id] : ids) id = i++;
  if (count) *count = i;
  std::vector<int> out;
  for (const auto& k : key) out.push_back(ids.at(k));
  return out;
}

}  // namespace depthbias::gap
