#include "detect/config_yaml.h"

#include <cmath>
#include <set>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

namespace depthbias::detect {
namespace {

struct ParseError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string Text(const YAML::Node& n) {
  if (n.IsScalar()) return "'" + n.Scalar() + "'";
  if (n.IsSequence()) return "a list";
  if (n.IsMap()) return "a map";
  return "nothing";
}

// A map whose keys are checked against the ones read from it.
class MapReader {
 public:
  MapReader(const YAML::Node& node, std::string where) : node_(node), where_(std::move(where)) {
    if (!node_.IsMap()) throw ParseError(where_ + ": expected a map, got " + Text(node_));
  }
  void Double(const std::string& key, double* out) {
    if (const YAML::Node n = Get(key)) {
      double v = 0;
      size_t used = 0;
      const std::string s = n.IsScalar() ? n.Scalar() : "";
      try {
        v = std::stod(s, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used == 0 || used != s.size() || !std::isfinite(v))
        throw ParseError(Where(key) + ": expected a number, got " + Text(n));
      *out = v;
    }
  }
  void Int(const std::string& key, int* out) {
    double v = *out;
    Double(key, &v);
    if (v != std::floor(v) || std::fabs(v) > 1e9)
      throw ParseError(Where(key) + ": expected a whole number");
    *out = static_cast<int>(v);
  }
  void Seed(const std::string& key, std::uint64_t* out) {
    double v = static_cast<double>(*out);
    Double(key, &v);
    if (v != std::floor(v) || v < 0 || v > 9007199254740992.0)
      throw ParseError(Where(key) + ": expected a whole number >= 0");
    *out = static_cast<std::uint64_t>(v);
  }
  void Bool(const std::string& key, bool* out) {
    if (const YAML::Node n = Get(key)) {
      const std::string s = n.IsScalar() ? n.Scalar() : "";
      if (s == "true" || s == "on" || s == "yes") {
        *out = true;
      } else if (s == "false" || s == "off" || s == "no") {
        *out = false;
      } else {
        throw ParseError(Where(key) + ": expected true or false, got " + Text(n));
      }
    }
  }
  YAML::Node Get(const std::string& key) {
    known_.insert(key);
    return node_[key];
  }
  std::string Where(const std::string& key) const {
    return where_.empty() ? key : where_ + "." + key;
  }
  void CheckKnown() const {
    for (const auto& kv : node_) {
      const std::string key = kv.first.Scalar();
      if (!known_.count(key)) throw ParseError("unknown key '" + Where(key) + "'");
    }
  }

 private:
  YAML::Node node_;
  std::string where_;
  std::set<std::string> known_;
};

}  // namespace

bool ParseDetectorYaml(const std::string& text, DetectorParams* params, std::string* why) {
  DetectorParams p = *params;
  try {
    YAML::Node root;
    try {
      root = YAML::Load(text);
    } catch (const YAML::Exception& e) {
      throw ParseError("not valid YAML: " + e.msg + " (line " + std::to_string(e.mark.line + 1) +
                       ")");
    }
    if (root.IsNull()) throw ParseError("empty document");
    MapReader top(root, "");
    if (const YAML::Node n = top.Get("cloud")) {
      MapReader r(n, "cloud");
      r.Int("stride_px", &p.cloud.stride_px);
      r.Double("min_range_m", &p.cloud.min_range_m);
      r.Double("max_range_m", &p.cloud.max_range_m);
      r.Double("min_valid_pct", &p.cloud.min_valid_pct);
      r.CheckKnown();
    }
    if (const YAML::Node n = top.Get("voxel")) {
      MapReader r(n, "voxel");
      r.Double("leaf_m", &p.voxel.leaf_m);
      r.Bool("use_pcl", &p.voxel.use_pcl);
      r.CheckKnown();
    }
    if (const YAML::Node n = top.Get("ground")) {
      MapReader r(n, "ground");
      r.Bool("enabled", &p.ground.enabled);
      r.Double("max_tilt_deg", &p.ground.max_tilt_deg);
      r.Double("distance_m", &p.ground.distance_m);
      r.Int("max_iterations", &p.ground.max_iterations);
      r.Double("probability", &p.ground.probability);
      r.Double("min_fraction", &p.ground.min_fraction);
      r.Int("refine_iterations", &p.ground.refine_iterations);
      r.Seed("seed", &p.ground.seed);
      r.CheckKnown();
    }
    if (const YAML::Node n = top.Get("cluster")) {
      MapReader r(n, "cluster");
      r.Double("base_tolerance_m", &p.cluster.base_tolerance_m);
      r.Double("noise_k", &p.cluster.noise_k);
      r.Double("disparity_noise_px", &p.cluster.disparity_noise_px);
      r.Int("min_points", &p.cluster.min_points);
      r.Bool("use_pcl", &p.cluster.use_pcl);
      r.CheckKnown();
    }
    if (const YAML::Node n = top.Get("obstacle")) {
      MapReader r(n, "obstacle");
      r.Double("min_height_m", &p.obstacle.min_height_m);
      r.Int("min_points", &p.obstacle.min_points);
      r.CheckKnown();
    }
    if (const YAML::Node n = top.Get("zones")) {
      MapReader r(n, "zones");
      r.Double("speed_mps", &p.zones.speed_mps);
      r.Double("reaction_s", &p.zones.reaction_s);
      r.Double("decel_mps2", &p.zones.decel_mps2);
      r.Double("clearance_m", &p.zones.clearance_m);
      r.Double("slow_margin_m", &p.zones.slow_margin_m);
      r.CheckKnown();
    }
    if (const YAML::Node n = top.Get("noise")) {
      MapReader r(n, "noise");
      r.Bool("from_frames", &p.noise.from_frames);
      r.Int("frames", &p.noise.frames);
      r.Int("min_pairs", &p.noise.min_pairs);
      r.CheckKnown();
    }
    top.Double("k", &p.k);
    top.Bool("safe_beyond_raw", &p.safe_beyond_raw);
    top.CheckKnown();
    std::string invalid;
    if (!p.IsValid(&invalid)) throw ParseError(invalid);
  } catch (const ParseError& e) {
    if (why) *why = e.what();
    return false;
  } catch (const YAML::Exception& e) {
    if (why) *why = "YAML: " + e.msg;
    return false;
  }
  *params = p;
  return true;
}

}  // namespace depthbias::detect
