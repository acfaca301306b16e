#include "sim/effects.h"

#include <cmath>
#include <sstream>

namespace depthbias::sim {
namespace {

// The registry. An entry: name, cause, signature, parameters (name, default, min, max, unit,
// meaning), and how it changes the departures. f = focal [px], B = baseline [m], Z = depth [m].
std::vector<EffectInfo> MakeRegistry() {
  std::vector<EffectInfo> r;
  r.push_back({"disparity_offset",
               "stereo calibration error or thermal drift of the rectification: every disparity "
               "is read δ px too large",
               "median depth moves by ΔZ ≈ −δ·Z²/(f·B), the same in every cell at a given Z; "
               "plane_std and valid_pct unchanged",
               {{"delta_px", 0.1, -2.0, 2.0, "px", "disparity offset δ"}},
               [](const std::map<std::string, double>& p, Departures* d) {
                 const double delta = p.at("delta_px");
                 d->static_disparity.push_back([delta](double, double) { return delta; });
               }});
  r.push_back({"depth_scale",
               "baseline, focal length or depth-unit error: every depth is scaled",
               "median depth moves by ΔZ = s·Z (linear in Z, unlike a disparity offset); "
               "plane_std scales by (1 + s)",
               {{"scale_rel", 0.01, -0.5, 0.5, "1", "relative scale error s: Z' = (1 + s)·Z"}},
               [](const std::map<std::string, double>& p, Departures* d) {
                 d->depth_scale *= 1.0 + p.at("scale_rel");
               }});
  r.push_back({"range_vs_depth",
               "the nominal distance was meant as a range but the panel was placed by depth, or "
               "the reverse (the protocol's distance_is names the meaning assumed)",
               "off-axis cells only: ΔZ = ±w·R·(1 − cos α) for a range R at off-axis angle α "
               "(nearer under distance_is: depth, farther under range); none at 0°",
               {{"weight", 1.0, 0.0, 1.0, "1", "share of the other meaning, 1 = fully the other"}},
               [](const std::map<std::string, double>& p, Departures* d) {
                 d->range_vs_depth_weight += p.at("weight");
               }});
  r.push_back({"radial_disparity_residual",
               "rectification residual that grows with the distance from the image centre "
               "(lens model or calibration error at the field's edge)",
               "Δd = k·r² with r the normalized image radius (tan of the off-axis angle): "
               "ΔZ ≈ −k·tan²α·Z²/(f·B), zero on axis, growing with Z² and α",
               {{"k_px", 0.1, -2.0, 2.0, "px", "disparity residual at r = 1 (45° off-axis)"}},
               [](const std::map<std::string, double>& p, Departures* d) {
                 const double k = p.at("k_px");
                 d->static_disparity.push_back(
                     [k](double xn, double yn) { return k * (xn * xn + yn * yn); });
               }});
  r.push_back({"edge_mixing",
               "the matching window straddles a depth edge, so pixels near the panel's outline "
               "take a disparity between the panel's and the background's (flying pixels)",
               "mean pulled from the median towards the background, plane_std up, worse as the "
               "panel shrinks in the image (edge share ∝ w·Z); median nearly unchanged",
               {{"width_px", 3.0, 1.0, 20.0, "px", "pixels this near an edge mix (floor)"},
                {"strength", 0.5, 0.0, 1.0, "1",
                 "largest mixing fraction, uniform in [0, strength] per pixel and frame"}},
               [](const std::map<std::string, double>& p, Departures* d) {
                 d->edge_mix_width_px = std::floor(p.at("width_px"));
                 d->edge_mix_strength = p.at("strength");
               }});
  r.push_back({"disparity_noise_gain",
               "more disparity noise than the base model: sunlight saturating the imagers, "
               "weaker texture, a shorter exposure",
               "plane_std and temporal_std multiplied by g (while σ_d dominates the quantization); "
               "median unchanged",
               {{"gain", 1.5, 0.0, 20.0, "1", "factor g on σ_d"}},
               [](const std::map<std::string, double>& p, Departures* d) {
                 d->sigma_gain *= p.at("gain");
               }});
  r.push_back({"invalidation_gain",
               "the valid-pixel probability differs from the base model: the preset's confidence "
               "thresholds, the light, the texture",
               "hole odds multiplied by g: hole rate p → g·p / (1 − p + g·p); depth unchanged",
               {{"gain", 2.0, 0.0, 1000.0, "1", "factor g on the odds of a hole"}},
               [](const std::map<std::string, double>& p, Departures* d) {
                 d->invalid_odds_gain *= p.at("gain");
               }});
  r.push_back({"emitter_gain",
               "the projector's pattern adds more or less texture than the base model: its power, "
               "the ambient infrared that washes it out (sunlight), the surface's reflectance "
               "in the near infrared",
               "emitter-on recordings only: the texture the emitter adds, e·t_e·min(1, (R_e/Z)²), "
               "so valid_pct moves most at short range (R_e the emitter's reach) and not at all "
               "with the emitter off; depths unchanged; e = 0: the projector adds nothing",
               {{"gain", 0.5, 0.0, 10.0, "1", "factor e on the emitter's texture"}},
               [](const std::map<std::string, double>& p, Departures* d) {
                 d->emitter_gain *= p.at("gain");
               }});
  r.push_back({"panel_tilt",
               "the panel is not parallel to the image plane: turned about the vertical",
               "normal_tilt_deg ≈ yaw; the depths spread across the panel (Z varies by "
               "width·sin(yaw)); median almost unchanged; panel narrower in the image",
               {{"yaw_deg", 10.0, -80.0, 80.0, "deg", "extra turn about the vertical"}},
               [](const std::map<std::string, double>& p, Departures* d) {
                 d->panel_yaw_deg += p.at("yaw_deg");
               }});
  r.push_back({"temporal_drift",
               "the disparity offset drifts during a recording (the projector and imagers warm up)",
               "a disparity offset δ(t) = rate·t: median moves by ≈ −rate·(T/2)·Z²/(f·B) over a "
               "recording of duration T, temporal_std up",
               {{"rate_px_per_s", 0.01, -1.0, 1.0, "px/s", "drift rate of the disparity offset"}},
               [](const std::map<std::string, double>& p, Departures* d) {
                 const double rate = p.at("rate_px_per_s");
                 d->disparity_over_time.push_back([rate](double t_s) { return rate * t_s; });
               }});
  r.push_back({"region_spill",
               "the panel's region is drawn larger than the panel (by hand, or a detector's box "
               "with a margin), so it takes in pixels of what lies behind the panel; a "
               "background within range (the field, trees, the ground beyond) gives them valid, "
               "far depths, the more so with a permissive preset",
               "mean pulled far from the median: a share q of the valid samples sits at the "
               "background's depth r·Z, mean − median ≈ q·(r − 1)·Z, q ∝ w/(panel size in px) "
               "∝ w·Z, so it grows with distance; plane_std and panel_width up; the median "
               "moves far only when q nears one half; none for w = 0",
               {{"width_px", 2.0, 0.0, 5.0, "px",
                 "how far the region reaches beyond the panel's outline, whole pixels (floor; at "
                 "most 5: the metrics-only path renders the panel's box padded by the edge band "
                 "+ 3 px)"},
                {"background_rel", 2.0, 1.05, 5.0, "1",
                 "depth of the background behind the panel over the panel's depth"}},
               [](const std::map<std::string, double>& p, Departures* d) {
                 d->region_spill_px += std::floor(p.at("width_px"));
                 d->background_depth_rel = p.at("background_rel");
               }});
  return r;
}

std::string Number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

double Departures::StaticDisparityPx(double xn, double yn) const {
  double sum = 0;
  for (const auto& f : static_disparity) sum += f(xn, yn);
  return sum;
}

double Departures::DisparityAtTimePx(double time_s) const {
  double sum = 0;
  for (const auto& f : disparity_over_time) sum += f(time_s);
  return sum;
}

bool Departures::OnlyEmitter() const {
  // Every field but emitter_gain, against its default (a field added to Departures is added here).
  const Departures none;
  return range_vs_depth_weight == none.range_vs_depth_weight &&
         panel_yaw_deg == none.panel_yaw_deg && sigma_gain == none.sigma_gain &&
         invalid_odds_gain == none.invalid_odds_gain && depth_scale == none.depth_scale &&
         edge_mix_width_px == none.edge_mix_width_px &&
         edge_mix_strength == none.edge_mix_strength &&
         region_spill_px == none.region_spill_px &&
         background_depth_rel == none.background_depth_rel && static_disparity.empty() &&
         disparity_over_time.empty();
}

bool Departures::SameButSpill(const Departures& o) const {
  // Every field but region_spill_px (a field added to Departures is added here).
  return range_vs_depth_weight == o.range_vs_depth_weight && panel_yaw_deg == o.panel_yaw_deg &&
         sigma_gain == o.sigma_gain && invalid_odds_gain == o.invalid_odds_gain &&
         emitter_gain == o.emitter_gain && depth_scale == o.depth_scale &&
         edge_mix_width_px == o.edge_mix_width_px && edge_mix_strength == o.edge_mix_strength &&
         background_depth_rel == o.background_depth_rel && static_disparity.empty() &&
         o.static_disparity.empty() && disparity_over_time.empty() &&
         o.disparity_over_time.empty();
}

const std::vector<EffectInfo>& EffectRegistry() {
  static const std::vector<EffectInfo> registry = MakeRegistry();
  return registry;
}

const EffectInfo* FindEffect(const std::string& name) {
  for (const auto& e : EffectRegistry())
    if (e.name == name) return &e;
  return nullptr;
}

std::string KnownEffectNames() {
  std::string s;
  for (const auto& e : EffectRegistry()) s += (s.empty() ? "" : ", ") + e.name;
  return s;
}

bool BuildDepartures(const std::vector<EffectSpec>& effects, Departures* out, std::string* why) {
  Departures d;
  for (size_t i = 0; i < effects.size(); ++i) {
    const EffectSpec& spec = effects[i];
    const std::string where = "effect " + std::to_string(i + 1) + " (" + spec.name + ")";
    const EffectInfo* info = FindEffect(spec.name);
    if (!info) {
      if (why) *why = where + ": unknown effect; known: " + KnownEffectNames();
      return false;
    }
    std::map<std::string, double> values;
    for (const auto& p : info->params) values[p.name] = p.default_value;
    for (const auto& [name, value] : spec.params) {
      const EffectParamInfo* param = nullptr;
      for (const auto& p : info->params)
        if (p.name == name) param = &p;
      if (!param) {
        std::string known;
        for (const auto& p : info->params) known += (known.empty() ? "" : ", ") + p.name;
        if (why) *why = where + ": unknown parameter '" + name + "'; known: " + known;
        return false;
      }
      if (!std::isfinite(value) || value < param->min_value || value > param->max_value) {
        if (why)
          *why = where + ": " + name + " = " + Number(value) + " is outside [" +
                 Number(param->min_value) + ", " + Number(param->max_value) + "] " + param->unit;
        return false;
      }
      values[name] = value;
    }
    info->apply(values, &d);
  }
  if (d.range_vs_depth_weight > 1.0) {
    if (why) *why = "range_vs_depth: the weights add up to more than 1";
    return false;
  }
  *out = std::move(d);
  return true;
}

}  // namespace depthbias::sim
