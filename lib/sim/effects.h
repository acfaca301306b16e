#pragma once
// Named departures from the base sensor model. Each effect has a physical cause, a signature in
// the metrics, and parameters with defaults, units and bounds (lib/sim/README.md lists them).
// An effect acts only through Departures, the sum of what the active effects change; adding an
// effect that uses these hooks is one new entry in the registry (effects.cpp).

#include <functional>
#include <map>
#include <string>
#include <vector>

namespace depthbias::sim {

// What the active effects change, accumulated over them.
struct Departures {
  // Scene.
  double range_vs_depth_weight = 0.0;  // 0: placed as the protocol says; 1: the other meaning
  double panel_yaw_deg = 0.0;          // added to the scene's panel yaw [deg]
  // Sensor.
  double sigma_gain = 1.0;         // multiplies σ_d
  double invalid_odds_gain = 1.0;  // multiplies the odds p/(1 − p) of a hole
  double emitter_gain = 1.0;       // multiplies the texture the emitter's pattern adds
  double depth_scale = 1.0;        // multiplies every reported depth
  double edge_mix_width_px = 0.0;  // pixels this near a depth edge mix with its other side
  double edge_mix_strength = 0.0;  // largest mixing fraction, drawn uniformly per pixel and frame
  // Measurement region and background (region_spill).
  double region_spill_px = 0.0;       // the panel's region reaches this far beyond its outline [px]
  double background_depth_rel = 0.0;  // > 0: the background behind the panel at this multiple of
                                      // the panel's depth (its forward distance); 0: the scene's
  // Additive disparity terms [px]: static ones of the pixel's normalized ray (x/z, y/z), and
  // ones of the time since the recording's first frame [s].
  std::vector<std::function<double(double x_normalized, double y_normalized)>> static_disparity;
  std::vector<std::function<double(double time_s)>> disparity_over_time;

  double StaticDisparityPx(double xn, double yn) const;
  double DisparityAtTimePx(double time_s) const;
  // True when every field but emitter_gain holds its default (no departure): a recording with
  // the emitter off is then simulated exactly as with no departures at all (emitter_gain is read
  // for emitter-on recordings alone).
  bool OnlyEmitter() const;
  // True when every field but region_spill_px holds the same value in both and neither has an
  // additive disparity term (functions are not compared): the two then simulate alike up to the
  // drawn region's width.
  bool SameButSpill(const Departures& other) const;
};

// One effect as the user names it: {name: disparity_offset, delta_px: 0.2}.
struct EffectSpec {
  std::string name;
  std::map<std::string, double> params;
};

struct EffectParamInfo {
  std::string name;
  double default_value;
  double min_value;  // inclusive bounds
  double max_value;
  std::string unit;
  std::string meaning;
};

struct EffectInfo {
  std::string name;
  std::string cause;      // the physical reason it happens
  std::string signature;  // how it shows in the metrics, with its formula
  std::vector<EffectParamInfo> params;
  // Adds the effect, with every parameter present and in bounds, to the departures.
  std::function<void(const std::map<std::string, double>& params, Departures* out)> apply;
};

// Every known effect, in a fixed order.
const std::vector<EffectInfo>& EffectRegistry();
const EffectInfo* FindEffect(const std::string& name);
std::string KnownEffectNames();  // "disparity_offset, depth_scale, ..."

// Checks names, parameter names and bounds, fills in defaults, and accumulates the departures.
// Returns false with a one-line reason (naming the effect's position and name) on any error.
bool BuildDepartures(const std::vector<EffectSpec>& effects, Departures* out, std::string* why);

}  // namespace depthbias::sim
