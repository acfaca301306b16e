#include "sim/config_yaml.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <set>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

namespace depthbias::sim {
namespace {

struct ParseError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// What a node is, for an error line: a scalar quoted (cut at 40 characters, on one line).
std::string Text(const YAML::Node& n) {
  if (n.IsScalar()) {
    std::string s = n.Scalar();
    for (char& c : s)
      if (c == '\n' || c == '\r') c = ' ';
    return "'" + (s.size() > 40 ? s.substr(0, 40) + "...'" : s + "'");
  }
  if (n.IsSequence()) return "a list";
  if (n.IsMap()) return "a map";
  return "nothing";
}

double ToDouble(const YAML::Node& n, const std::string& where) {
  if (n.IsScalar()) {
    const std::string& s = n.Scalar();
    try {
      size_t used = 0;
      const double v = std::stod(s, &used);
      if (used == s.size() && std::isfinite(v)) return v;
    } catch (const std::exception&) {
    }
  }
  throw ParseError(where + ": expected a number, got " + Text(n));
}

int ToInt(const YAML::Node& n, const std::string& where) {
  const double v = ToDouble(n, where);
  if (v != std::floor(v) || std::fabs(v) > 1e9)
    throw ParseError(where + ": expected a whole number, got " + Text(n));
  return static_cast<int>(v);
}

std::string ToString(const YAML::Node& n, const std::string& where) {
  if (!n.IsScalar() || n.Scalar().empty())
    throw ParseError(where + ": expected a word, got " + Text(n));
  return n.Scalar();
}

bool ToOnOff(const YAML::Node& n, const std::string& where) {
  const std::string s = n.IsScalar() ? n.Scalar() : "";
  if (s == "on" || s == "true" || s == "yes" || s == "1") return true;
  if (s == "off" || s == "false" || s == "no" || s == "0") return false;
  throw ParseError(where + ": expected on or off, got " + Text(n));
}

template <typename T, typename F>
std::vector<T> ToList(const YAML::Node& n, const std::string& where, F convert) {
  if (!n.IsSequence()) throw ParseError(where + ": expected a list, got " + Text(n));
  std::vector<T> out;
  for (size_t i = 0; i < n.size(); ++i)
    out.push_back(convert(n[i], where + "[" + std::to_string(i) + "]"));
  return out;
}

// A map whose keys are checked against the ones read from it.
class MapReader {
 public:
  MapReader(const YAML::Node& node, std::string where) : node_(node), where_(std::move(where)) {
    if (!node_.IsMap()) throw ParseError(where_ + ": expected a map, got " + Text(node_));
  }
  YAML::Node Get(const std::string& key) {
    known_.insert(key);
    return node_[key];
  }
  std::string Where(const std::string& key) const { return where_ + "." + key; }
  void Double(const std::string& key, double* out) {
    const YAML::Node n = Get(key);
    if (n) *out = ToDouble(n, Where(key));
  }
  void Int(const std::string& key, int* out) {
    const YAML::Node n = Get(key);
    if (n) *out = ToInt(n, Where(key));
  }
  void String(const std::string& key, std::string* out) {
    const YAML::Node n = Get(key);
    if (n) *out = ToString(n, Where(key));
  }
  void CheckKnown() const {
    for (const auto& kv : node_) {
      const std::string key = kv.first.Scalar();
      if (!known_.count(key)) throw ParseError(where_ + ": unknown key '" + key + "'");
    }
  }

 private:
  YAML::Node node_;
  std::string where_;
  std::set<std::string> known_;
};

YAML::Node Load(const std::string& text) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ParseError("not valid YAML: " + e.msg + " (line " + std::to_string(e.mark.line + 1) +
                     ")");
  }
}

void ReadScenario(MapReader& r, ScenarioParams* s) {
  r.Double("sigma_d_px", &s->sigma_d_px);
  r.Double("invalid_prob", &s->invalid_prob);
}

// scene.obstacles: [{kind: person, range_m: 5, azimuth_deg: -10}, {kind: bush, ...}]; a kind's
// sizes and texture (ObstacleOfKind) unless named.
std::vector<Obstacle> ReadObstacles(const YAML::Node& n, const std::string& where) {
  if (!n.IsSequence()) throw ParseError(where + ": expected a list, got " + Text(n));
  std::vector<Obstacle> out;
  for (size_t i = 0; i < n.size(); ++i) {
    MapReader r(n[i], where + "[" + std::to_string(i) + "]");
    std::string kind = "person";
    r.String("kind", &kind);
    Obstacle o;
    if (!ObstacleOfKind(kind, &o))
      throw ParseError(r.Where("kind") + ": unknown kind '" + kind +
                       "' (person, bush, box, ellipsoid)");
    if (!r.Get("range_m") || !r.Get("azimuth_deg"))
      throw ParseError(r.Where("range_m") + " and azimuth_deg are required");
    r.Double("range_m", &o.range_m);
    r.Double("azimuth_deg", &o.azimuth_deg);
    r.Double("width_m", &o.width_m);
    r.Double("depth_m", &o.depth_m);
    r.Double("height_m", &o.height_m);
    r.Double("texture", &o.texture);
    r.CheckKnown();
    out.push_back(o);
  }
  return out;
}

template <typename F>
bool Guard(std::string* why, F body) {
  try {
    body();
    return true;
  } catch (const ParseError& e) {
    if (why) *why = e.what();
  } catch (const YAML::Exception& e) {
    if (why) *why = "YAML: " + e.msg;
  }
  return false;
}

std::string Num(double v) {
  std::ostringstream s;
  s << std::setprecision(10) << v;
  return s.str();
}

}  // namespace

bool ParseProtocolYaml(const std::string& text, ProtocolParams* protocol,
                       std::string* sensor_file, std::string* why) {
  ProtocolParams p = *protocol;
  std::string sensor;
  const bool ok = Guard(why, [&] {
    const YAML::Node root = Load(text);
    MapReader top(root, "document");
    if (const YAML::Node n = top.Get("protocol")) {
      MapReader r(n, "protocol");
      if (auto v = r.Get("distances_m"))
        p.distances_m = ToList<double>(v, r.Where("distances_m"), ToDouble);
      if (auto v = r.Get("angles_deg"))
        p.angles_deg = ToList<double>(v, r.Where("angles_deg"), ToDouble);
      if (auto v = r.Get("presets"))
        p.presets = ToList<std::string>(v, r.Where("presets"), ToString);
      if (auto v = r.Get("emitters")) p.emitters = ToList<bool>(v, r.Where("emitters"), ToOnOff);
      if (auto v = r.Get("lights")) p.lights = ToList<std::string>(v, r.Where("lights"), ToString);
      std::string meaning;
      r.String("distance_is", &meaning);
      if (!meaning.empty() && !ParseDistanceIs(meaning, &p.distance_is))
        throw ParseError("protocol.distance_is: expected range or depth, got '" + meaning + "'");
      r.Int("frames", &p.frames);
      r.Double("fps", &p.fps);
      r.CheckKnown();
    }
    if (const YAML::Node n = top.Get("scene")) {
      MapReader r(n, "scene");
      SceneParams& s = p.scene;
      r.Double("camera_height_m", &s.camera_height_m);
      r.Double("camera_pitch_deg", &s.camera_pitch_deg);
      r.Double("camera_roll_deg", &s.camera_roll_deg);
      r.Double("ground_texture", &s.ground_texture);
      r.Double("panel_width_m", &s.panel_width_m);
      r.Double("panel_height_m", &s.panel_height_m);
      r.Double("panel_center_height_m", &s.panel_center_height_m);
      r.Double("panel_yaw_deg", &s.panel_yaw_deg);
      r.Double("panel_texture", &s.panel_texture);
      r.Double("background_distance_m", &s.background_distance_m);
      r.Double("background_texture", &s.background_texture);
      if (auto v = r.Get("panel")) s.panel = ToOnOff(v, r.Where("panel"));
      if (auto v = r.Get("obstacles")) s.obstacles = ReadObstacles(v, r.Where("obstacles"));
      if (auto v = r.Get("hedge")) {
        MapReader h(v, r.Where("hedge"));
        h.Double("distance_m", &s.hedge.distance_m);
        h.Double("height_m", &s.hedge.height_m);
        h.Double("texture", &s.hedge.texture);
        h.CheckKnown();
      }
      r.CheckKnown();
    }
    top.String("sensor", &sensor);
    top.CheckKnown();
    std::string invalid;
    if (!p.IsValid(&invalid)) throw ParseError(invalid);
  });
  if (!ok) return false;
  *protocol = p;
  if (sensor_file) *sensor_file = sensor;
  return true;
}

bool ParseSensorYaml(const std::string& text, SensorParams* sensor, std::string* why) {
  SensorParams s = *sensor;
  const bool ok = Guard(why, [&] {
    const YAML::Node root = Load(text);
    MapReader top(root, "document");
    top.Get("calibration");  // the calibration's record, not a parameter
    MapReader r(top.Get("sensor"), "sensor");
    r.Int("width", &s.intrinsics.width);
    r.Int("height", &s.intrinsics.height);
    r.Double("fx", &s.intrinsics.fx);
    r.Double("fy", &s.intrinsics.fy);
    r.Double("ppx", &s.intrinsics.ppx);
    r.Double("ppy", &s.intrinsics.ppy);
    r.Double("baseline_m", &s.baseline_m);
    r.Double("depth_units_m", &s.depth_units_m);
    r.Double("subpixel_step_px", &s.subpixel_step_px);
    r.Double("min_depth_m", &s.min_depth_m);
    r.Double("max_depth_m", &s.max_depth_m);
    r.Double("texture_slope", &s.texture_slope);
    r.Double("reference_texture", &s.reference_texture);
    r.Double("emitter_texture", &s.emitter_texture);
    r.Double("emitter_reach_m", &s.emitter_reach_m);
    r.Double("edge_jump_rel", &s.edge_jump_rel);
    r.Int("edge_band_px", &s.edge_band_px);
    r.Double("edge_invalid_prob", &s.edge_invalid_prob);
    if (const YAML::Node n = r.Get("fallback")) {
      MapReader f(n, "sensor.fallback");
      ReadScenario(f, &s.fallback);
      f.CheckKnown();
    }
    if (const YAML::Node n = r.Get("scenarios")) {
      if (!n.IsSequence()) throw ParseError("sensor.scenarios: expected a list, got " + Text(n));
      s.scenarios.clear();
      for (size_t i = 0; i < n.size(); ++i) {
        MapReader e(n[i], "sensor.scenarios[" + std::to_string(i) + "]");
        ScenarioParams sc = s.fallback;
        e.String("light", &sc.light);
        e.String("preset", &sc.preset);
        if (sc.light.empty() || sc.preset.empty())
          throw ParseError(e.Where("light") + " and preset are required");
        ReadScenario(e, &sc);
        e.CheckKnown();
        s.scenarios.push_back(sc);
      }
    }
    r.CheckKnown();
    top.CheckKnown();
    std::string invalid;
    if (!s.IsValid(&invalid)) throw ParseError("sensor: " + invalid);
  });
  if (!ok) return false;
  *sensor = s;
  return true;
}

bool ParseEffectsYaml(const std::string& text, std::vector<EffectSpec>* effects,
                      std::string* why) {
  std::vector<EffectSpec> out;
  const bool ok = Guard(why, [&] {
    const YAML::Node root = Load(text);
    MapReader top(root, "document");
    const YAML::Node list = top.Get("effects");
    top.CheckKnown();
    if (!list) throw ParseError("document: no 'effects' list");
    if (list.IsNull()) return;
    if (!list.IsSequence()) throw ParseError("effects: expected a list, got " + Text(list));
    for (size_t i = 0; i < list.size(); ++i) {
      const std::string where = "effects[" + std::to_string(i) + "]";
      if (!list[i].IsMap()) throw ParseError(where + ": expected a map, got " + Text(list[i]));
      EffectSpec spec;
      if (!list[i]["name"]) throw ParseError(where + ": no name");
      spec.name = ToString(list[i]["name"], where + ".name");
      const EffectInfo* info = FindEffect(spec.name);
      if (!info)
        throw ParseError(where + ": unknown effect '" + spec.name + "'; known: " +
                         KnownEffectNames());
      for (const auto& kv : list[i]) {
        const std::string key = kv.first.Scalar();
        if (key == "name") continue;
        bool known = false;
        for (const auto& p : info->params) known |= p.name == key;
        if (!known) {
          std::string names;
          for (const auto& p : info->params) names += (names.empty() ? "" : ", ") + p.name;
          throw ParseError(where + " (" + spec.name + "): unknown parameter '" + key +
                           "'; known: " + names);
        }
        spec.params[key] = ToDouble(kv.second, where + "." + key);
      }
      out.push_back(spec);
    }
    Departures unused;
    std::string invalid;
    if (!BuildDepartures(out, &unused, &invalid)) throw ParseError(invalid);
  });
  if (!ok) return false;
  *effects = out;
  return true;
}

std::string FormatSensorYaml(const SensorParams& s, const std::vector<std::string>& comments,
                             const std::string& extra_yaml) {
  std::ostringstream o;
  for (const auto& c : comments) o << "# " << c << "\n";
  const auto& in = s.intrinsics;
  o << "sensor:\n"
    << "  width: " << in.width << "\n  height: " << in.height << "\n"
    << "  fx: " << Num(in.fx) << "\n  fy: " << Num(in.fy) << "\n"
    << "  ppx: " << Num(in.ppx) << "\n  ppy: " << Num(in.ppy) << "\n"
    << "  baseline_m: " << Num(s.baseline_m) << "\n"
    << "  depth_units_m: " << Num(s.depth_units_m) << "\n"
    << "  subpixel_step_px: " << Num(s.subpixel_step_px) << "\n"
    << "  min_depth_m: " << Num(s.min_depth_m) << "\n"
    << "  max_depth_m: " << Num(s.max_depth_m) << "\n"
    << "  texture_slope: " << Num(s.texture_slope) << "\n"
    << "  reference_texture: " << Num(s.reference_texture) << "\n"
    << "  emitter_texture: " << Num(s.emitter_texture) << "\n"
    << "  emitter_reach_m: " << Num(s.emitter_reach_m) << "\n"
    << "  edge_jump_rel: " << Num(s.edge_jump_rel) << "\n"
    << "  edge_band_px: " << s.edge_band_px << "\n"
    << "  edge_invalid_prob: " << Num(s.edge_invalid_prob) << "\n"
    << "  fallback: {sigma_d_px: " << Num(s.fallback.sigma_d_px)
    << ", invalid_prob: " << Num(s.fallback.invalid_prob) << "}\n"
    << "  scenarios:\n";
  for (const auto& sc : s.scenarios)
    o << "    - {light: " << sc.light << ", preset: " << sc.preset
      << ", sigma_d_px: " << Num(sc.sigma_d_px) << ", invalid_prob: " << Num(sc.invalid_prob)
      << "}\n";
  o << extra_yaml;
  return o.str();
}

void ApplyRecording(const camera::Intrinsics& intrinsics, double depth_units_m,
                    const std::map<std::string, double>& options, SensorParams* sensor) {
  sensor->intrinsics = intrinsics;
  sensor->intrinsics.model = camera::Distortion::kNone;
  sensor->intrinsics.coeffs = {0, 0, 0, 0, 0};
  if (depth_units_m > 0) {
    sensor->depth_units_m = depth_units_m;
    // The camera's own range at these units: 16-bit counts.
    sensor->max_depth_m = std::min(sensor->max_depth_m, 65535 * depth_units_m);
  }
  const auto baseline = options.find("Stereo_Baseline");
  if (baseline != options.end() && baseline->second > 0)
    sensor->baseline_m = baseline->second / 1000.0;
}

}  // namespace depthbias::sim
