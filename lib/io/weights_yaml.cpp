#include "io/weights_yaml.h"

#include <cmath>
#include <initializer_list>

#include <yaml-cpp/yaml.h>

#include "io/atomic_file.h"
#include "io/csv.h"
#include "io/ranges.h"
#include "io/yaml_limits.h"

namespace depthbias::io {
namespace {

constexpr const char* kSchema = "depthbias.weights/2";
constexpr const char* kSchemaV1 = "depthbias.weights/1";  // no margin, no near guard: read only

std::string Num(double v) {
  if (std::isnan(v)) return ".nan";
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  return CsvNumber(v);
}

// Reading with errors that name the file and the key.
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}
  [[noreturn]] void Fail(const std::string& key, const std::string& what) const {
    throw IoError(file_ + ": " + (key.empty() ? "" : "key '" + key + "': ") + what);
  }
  YAML::Node Need(const YAML::Node& parent, const std::string& name,
                  const std::string& path) const {
    const YAML::Node n = parent[name];
    if (!n) Fail(path, "missing");
    return n;
  }
  double Double(const YAML::Node& n, const std::string& path) const {
    if (!n.IsScalar()) Fail(path, "expected a number");
    try {
      return n.as<double>();
    } catch (const YAML::Exception&) {
      Fail(path, "'" + n.Scalar() + "' is not a number");
    }
  }
  int Int(const YAML::Node& n, const std::string& path) const {
    if (!n.IsScalar()) Fail(path, "expected an integer");
    try {
      return n.as<int>();
    } catch (const YAML::Exception&) {
      Fail(path, "'" + n.Scalar() + "' is not an integer");
    }
  }
  bool Bool(const YAML::Node& n, const std::string& path) const {
    if (!n.IsScalar()) Fail(path, "expected true or false");
    try {
      return n.as<bool>();
    } catch (const YAML::Exception&) {
      Fail(path, "'" + n.Scalar() + "' is not true or false");
    }
  }
  // A number within `rule`; NaN too when `nan_ok` (a value the fit could not give: n <= p).
  double Checked(const YAML::Node& n, const std::string& path, const NumberRule& rule,
                 bool nan_ok = false) const {
    const double v = Double(n, path);
    if (nan_ok && std::isnan(v)) return v;
    const std::string why = rule.Why(v);
    if (!why.empty()) Fail(path, why);
    return v;
  }
  std::string String(const YAML::Node& n, const std::string& path) const {
    if (!n.IsScalar()) Fail(path, "expected a text value");
    return n.Scalar();
  }
  std::vector<double> Doubles(const YAML::Node& n, const std::string& path) const {
    if (!n.IsSequence()) Fail(path, "expected a list of numbers");
    std::vector<double> v;
    for (size_t i = 0; i < n.size(); ++i) {
      v.push_back(Double(n[i], path + "[" + std::to_string(i) + "]"));
    }
    return v;
  }
  // Fails on a key of map n that is not one of `known` (a misspelt key must not be ignored).
  void OnlyKeys(const YAML::Node& n, const std::string& path,
                std::initializer_list<const char*> known) const {
    for (const auto& kv : n) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "?";
      bool ok = false;
      for (const char* k : known) ok = ok || key == k;
      if (ok) continue;
      std::string list;
      for (const char* k : known) list += (list.empty() ? "" : ", ") + std::string(k);
      Fail(path.empty() ? key : path + "." + key, "unknown key (expected one of: " + list + ")");
    }
  }
  records::BiasCrossValidation Cv(const YAML::Node& n, const std::string& path) const {
    if (!n.IsMap()) Fail(path, "expected a map {scheme, rmse_m, mae_m}");
    const std::string scheme = String(Need(n, "scheme", path + ".scheme"), path + ".scheme");
    if (scheme != "none" && scheme != "point" && scheme != "distance" && scheme != "angle")
      Fail(path + ".scheme", "'" + scheme + "' (expected point, distance, angle or none)");
    return {scheme,
            Checked(Need(n, "rmse_m", path + ".rmse_m"), path + ".rmse_m", rules::kSpreadM, true),
            Checked(Need(n, "mae_m", path + ".mae_m"), path + ".mae_m", rules::kSpreadM, true)};
  }

 private:
  std::string file_;
};

constexpr NumberRule kAny{-rules::kInf, rules::kInf, true, true, ""};
constexpr NumberRule kPositive{0.0, rules::kInf, true, true, ""};

// A covariance of the weights: p x p, finite, variances >= 0 and no correlation beyond 1
// (|c_ij| <= sqrt(c_ii c_jj)). A negative variance would shrink the margin it widens.
void CheckCovariance(const Reader& r, const std::vector<std::vector<double>>& c, size_t p,
                     const std::string& path) {
  const std::string shape = std::to_string(p) + " x " + std::to_string(p);
  if (c.size() != p) r.Fail(path, "has " + std::to_string(c.size()) + " rows, expected " + shape);
  for (size_t i = 0; i < p; ++i) {
    const std::string row = path + "[" + std::to_string(i) + "]";
    if (c[i].size() != p)
      r.Fail(row, "has " + std::to_string(c[i].size()) + " entries, expected " + shape);
    for (size_t j = 0; j < p; ++j)
      if (!std::isfinite(c[i][j]))
        r.Fail(row + "[" + std::to_string(j) + "]", records::NumberText(c[i][j]) +
                                                        " is not a finite number");
    if (c[i][i] < 0)
      r.Fail(row + "[" + std::to_string(i) + "]",
             records::NumberText(c[i][i]) + " is a negative variance");
  }
  for (size_t i = 0; i < p; ++i)
    for (size_t j = 0; j < i; ++j) {
      const double bound = std::sqrt(c[i][i] * c[j][j]);
      const double tol = 1e-9 * (std::fabs(c[i][j]) + std::fabs(c[j][i]) + bound) + 1e-300;
      if (std::fabs(c[i][j] - c[j][i]) > tol)
        r.Fail(path, "is not symmetric (entry " + std::to_string(i) + "," + std::to_string(j) +
                         ": " + records::NumberText(c[i][j]) + " vs " +
                         records::NumberText(c[j][i]) + ")");
      if (std::fabs(c[i][j]) > bound * (1 + 1e-6) + 1e-300)
        r.Fail(path, "entry " + std::to_string(i) + "," + std::to_string(j) + " (" +
                         records::NumberText(c[i][j]) +
                         ") exceeds the square root of its variances' product: not a covariance");
    }
}

}  // namespace

std::string FormatWeightsYaml(const records::BiasWeights& w) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "schema" << YAML::Value << kSchema;
  out << YAML::Key << "model" << YAML::Value << w.model;
  out << YAML::Key << "target" << YAML::Value << w.target;
  out << YAML::Key << "lambda" << YAML::Value << Num(w.lambda);
  out << YAML::Key << "loss" << YAML::Value << w.loss;
  out << YAML::Key << "loss_scale_m" << YAML::Value << Num(w.loss_scale_m);
  out << YAML::Key << "focal_px" << YAML::Value << Num(w.focal_px);
  out << YAML::Key << "baseline_m" << YAML::Value << Num(w.baseline_m);
  out << YAML::Key << "group_by" << YAML::Value << YAML::Flow << w.group_by;
  out << YAML::Key << "near_guard" << YAML::Value << YAML::Flow << YAML::BeginMap
      << YAML::Key << "near_m" << YAML::Value << Num(w.near_m) << YAML::Key << "full_m"
      << YAML::Value << Num(w.full_m) << YAML::EndMap;
  out << YAML::Key << "noise_pooled" << YAML::Value << w.noise_pooled;
  out << YAML::Key << "groups" << YAML::Value << YAML::BeginSeq;
  for (const auto& g : w.groups) {
    out << YAML::BeginMap;
    out << YAML::Key << "light" << YAML::Value << g.light;
    out << YAML::Key << "preset" << YAML::Value << g.preset;
    if (g.emitter != "*") out << YAML::Key << "emitter" << YAML::Value << g.emitter;
    out << YAML::Key << "n" << YAML::Value << g.n;
    out << YAML::Key << "weights" << YAML::Value << YAML::BeginMap;
    for (size_t j = 0; j < g.names.size(); ++j) {
      out << YAML::Key << g.names[j] << YAML::Value << Num(g.values.at(j));
    }
    out << YAML::EndMap;
    if (!g.knots_deg.empty()) {
      out << YAML::Key << "knots_deg" << YAML::Value << YAML::Flow << YAML::BeginSeq;
      for (double k : g.knots_deg) out << Num(k);
      out << YAML::EndSeq;
    }
    out << YAML::Key << "rmse_m" << YAML::Value << Num(g.rmse_m);
    out << YAML::Key << "mae_m" << YAML::Value << Num(g.mae_m);
    out << YAML::Key << "residual_std_m" << YAML::Value << Num(g.residual_std_m);
    if (g.margin.known) {
      out << YAML::Key << "margin" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key
          << "placement_m" << YAML::Value << Num(g.margin.placement_m) << YAML::Key
          << "noise_per_m" << YAML::Value << Num(g.margin.noise_per_m) << YAML::Key
          << "weighted" << YAML::Value << g.margin.weighted << YAML::Key << "errors"
          << YAML::Value << g.margin.errors << YAML::EndMap;
    }
    if (g.disparity_noise.known) {
      out << YAML::Key << "disparity_noise" << YAML::Value << YAML::Flow << YAML::BeginMap
          << YAML::Key << "sigma_px" << YAML::Value << Num(g.disparity_noise.sigma_px)
          << YAML::Key << "recordings" << YAML::Value << g.disparity_noise.recordings
          << YAML::EndMap;
    }
    auto cv_map = [&out](const records::BiasCrossValidation& cv) {
      out << YAML::Flow << YAML::BeginMap << YAML::Key << "scheme" << YAML::Value << cv.scheme
          << YAML::Key << "rmse_m" << YAML::Value << Num(cv.rmse_m) << YAML::Key << "mae_m"
          << YAML::Value << Num(cv.mae_m) << YAML::EndMap;
    };
    out << YAML::Key << "cv" << YAML::Value;
    cv_map(g.cv.empty() ? records::BiasCrossValidation{"none", NAN, NAN} : g.cv.front());
    if (g.cv.size() > 1) {
      out << YAML::Key << "cv_more" << YAML::Value << YAML::BeginSeq;
      for (size_t i = 1; i < g.cv.size(); ++i) cv_map(g.cv[i]);
      out << YAML::EndSeq;
    }
    out << YAML::Key << "covariance" << YAML::Value << YAML::BeginSeq;
    for (const auto& row : g.covariance) {
      out << YAML::Flow << YAML::BeginSeq;
      for (double v : row) out << Num(v);
      out << YAML::EndSeq;
    }
    out << YAML::EndSeq;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "provenance" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "input_file" << YAML::Value << w.input_file;
  out << YAML::Key << "input_sha256" << YAML::Value << w.input_sha256;
  out << YAML::Key << "tool" << YAML::Value << w.tool;
  out << YAML::Key << "tool_version" << YAML::Value << w.tool_version;
  out << YAML::EndMap;
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

void WriteWeightsYaml(const std::string& path, const records::BiasWeights& weights) {
  WriteFileAtomic(path, FormatWeightsYaml(weights));
}

records::BiasWeights ParseWeightsYaml(const std::string& text, const std::string& file) {
  const Reader r(file);
  const YAML::Node root = LoadYaml(text, file);
  if (!root.IsMap()) r.Fail("", "not a depthbias weights file (expected a YAML map)");
  const std::string schema =
      root["schema"] && root["schema"].IsScalar() ? root["schema"].Scalar() : "";
  if (schema != kSchema && schema != kSchemaV1) {
    r.Fail("schema", std::string("not a depthbias weights file (expected schema: ") + kSchema +
                         " or " + kSchemaV1 + ")");
  }
  const bool v1 = schema == kSchemaV1;
  if (v1) {
    r.OnlyKeys(root, "",
               {"schema", "model", "target", "lambda", "loss", "loss_scale_m", "focal_px",
                "baseline_m", "group_by", "groups", "provenance"});
  } else {
    r.OnlyKeys(root, "",
               {"schema", "model", "target", "lambda", "loss", "loss_scale_m", "focal_px",
                "baseline_m", "group_by", "near_guard", "noise_pooled", "groups",
                "provenance"});
  }
  records::BiasWeights w;
  w.schema = schema;
  w.model = r.String(r.Need(root, "model", "model"), "model");
  if (root["target"]) w.target = r.String(root["target"], "target");
  w.lambda = r.Checked(r.Need(root, "lambda", "lambda"), "lambda", rules::kNonNegative);
  if (root["loss"]) w.loss = r.String(root["loss"], "loss");
  if (root["loss_scale_m"])
    w.loss_scale_m = r.Checked(root["loss_scale_m"], "loss_scale_m", kPositive);
  if (root["focal_px"]) w.focal_px = r.Checked(root["focal_px"], "focal_px", rules::kNonNegative);
  if (root["baseline_m"])
    w.baseline_m = r.Checked(root["baseline_m"], "baseline_m", rules::kNonNegative);
  if (root["group_by"]) {
    const YAML::Node gb = root["group_by"];
    if (!gb.IsSequence()) r.Fail("group_by", "expected a list");
    for (size_t i = 0; i < gb.size(); ++i) {
      w.group_by.push_back(r.String(gb[i], "group_by[" + std::to_string(i) + "]"));
    }
  }
  if (const YAML::Node ng = root["near_guard"]; ng) {
    if (!ng.IsMap()) r.Fail("near_guard", "expected a map {near_m, full_m}");
    r.OnlyKeys(ng, "near_guard", {"near_m", "full_m"});
    w.near_m = r.Double(r.Need(ng, "near_m", "near_guard.near_m"), "near_guard.near_m");
    w.full_m = r.Double(r.Need(ng, "full_m", "near_guard.full_m"), "near_guard.full_m");
    if (!(w.near_m >= 0) || !(w.full_m >= w.near_m)) {
      r.Fail("near_guard", "need 0 <= near_m <= full_m");
    }
  }
  if (root["noise_pooled"]) w.noise_pooled = r.Bool(root["noise_pooled"], "noise_pooled");
  const YAML::Node groups = r.Need(root, "groups", "groups");
  if (!groups.IsSequence() || groups.size() == 0) r.Fail("groups", "expected a non-empty list");
  for (size_t i = 0; i < groups.size(); ++i) {
    const std::string p = "groups[" + std::to_string(i) + "]";
    const YAML::Node gn = groups[i];
    if (!gn.IsMap()) r.Fail(p, "expected a map");
    if (v1) {
      r.OnlyKeys(gn, p,
                 {"light", "preset", "emitter", "n", "weights", "knots_deg", "rmse_m", "mae_m",
                  "residual_std_m", "cv", "cv_more", "covariance"});
    } else {
      r.OnlyKeys(gn, p,
                 {"light", "preset", "emitter", "n", "weights", "knots_deg", "rmse_m", "mae_m",
                  "residual_std_m", "margin", "disparity_noise", "cv", "cv_more",
                  "covariance"});
    }
    records::BiasWeightsGroup g;
    g.light = r.String(r.Need(gn, "light", p + ".light"), p + ".light");
    g.preset = r.String(r.Need(gn, "preset", p + ".preset"), p + ".preset");
    if (gn["emitter"]) g.emitter = r.String(gn["emitter"], p + ".emitter");
    g.n = r.Int(r.Need(gn, "n", p + ".n"), p + ".n");
    if (g.n < 1) r.Fail(p + ".n", std::to_string(g.n) + " rows; a fitted group has at least 1");
    const YAML::Node wn = r.Need(gn, "weights", p + ".weights");
    if (!wn.IsMap() || wn.size() == 0) r.Fail(p + ".weights", "expected a map name: value");
    for (const auto& kv : wn) {
      const std::string name = r.String(kv.first, p + ".weights");
      g.names.push_back(name);
      g.values.push_back(r.Checked(kv.second, p + ".weights." + name, kAny));
    }
    if (gn["knots_deg"]) {
      g.knots_deg = r.Doubles(gn["knots_deg"], p + ".knots_deg");
      for (size_t k = 0; k < g.knots_deg.size(); ++k) {
        const std::string why = rules::kOffAxisDeg.Why(g.knots_deg[k]);
        if (!why.empty()) r.Fail(p + ".knots_deg[" + std::to_string(k) + "]", why);
      }
    }
    g.rmse_m = r.Checked(r.Need(gn, "rmse_m", p + ".rmse_m"), p + ".rmse_m", rules::kSpreadM, true);
    g.mae_m = r.Checked(r.Need(gn, "mae_m", p + ".mae_m"), p + ".mae_m", rules::kSpreadM, true);
    // NaN: the fit had no degrees of freedom left (n <= p) and the scatter is unknown; the
    // model then claims no margin. A negative or infinite scatter is refused.
    if (gn["residual_std_m"]) {
      g.residual_std_m =
          r.Checked(gn["residual_std_m"], p + ".residual_std_m", rules::kSpreadM, true);
      if (std::isinf(g.residual_std_m * g.residual_std_m))
        r.Fail(p + ".residual_std_m", records::NumberText(g.residual_std_m) +
                                          " m: its square (a variance) overflows");
    }
    if (const YAML::Node mn = gn["margin"]; mn) {
      const std::string mp = p + ".margin";
      if (!mn.IsMap()) r.Fail(mp, "expected a map {placement_m, noise_per_m, weighted}");
      r.OnlyKeys(mn, mp, {"placement_m", "noise_per_m", "weighted", "errors"});
      g.margin.known = true;
      g.margin.placement_m = r.Checked(r.Need(mn, "placement_m", mp + ".placement_m"),
                                       mp + ".placement_m", rules::kSigmaM);
      g.margin.noise_per_m = r.Checked(r.Need(mn, "noise_per_m", mp + ".noise_per_m"),
                                       mp + ".noise_per_m", rules::kSigmaM);
      if (mn["weighted"]) g.margin.weighted = r.Bool(mn["weighted"], mp + ".weighted");
      if (mn["errors"]) {
        g.margin.errors = r.String(mn["errors"], mp + ".errors");
        if (g.margin.errors != "held_out" && g.margin.errors != "in_sample")
          r.Fail(mp + ".errors", "'" + g.margin.errors + "' (expected held_out or in_sample)");
      }
      // σ²(Z) = σ_place² + (c·Z²)² must stay a finite number out to the farthest depth any
      // reader accepts (rules::kDistanceM), or a margin comes out as ±inf.
      const double far_m = rules::kDistanceM.max;
      const double noise_m = g.margin.noise_per_m * far_m * far_m;
      if (!std::isfinite(g.margin.placement_m * g.margin.placement_m + noise_m * noise_m)) {
        r.Fail(mp, "placement_m " + records::NumberText(g.margin.placement_m) +
                       " and noise_per_m " + records::NumberText(g.margin.noise_per_m) +
                       " give a sigma that overflows at " + records::NumberText(far_m) + " m");
      }
    }
    if (const YAML::Node dn = gn["disparity_noise"]; dn) {
      const std::string dp = p + ".disparity_noise";
      if (!dn.IsMap()) r.Fail(dp, "expected a map {sigma_px, recordings}");
      r.OnlyKeys(dn, dp, {"sigma_px", "recordings"});
      g.disparity_noise.known = true;
      g.disparity_noise.sigma_px = r.Checked(r.Need(dn, "sigma_px", dp + ".sigma_px"),
                                             dp + ".sigma_px", rules::kDisparityNoisePx);
      g.disparity_noise.recordings =
          r.Int(r.Need(dn, "recordings", dp + ".recordings"), dp + ".recordings");
      if (g.disparity_noise.recordings < 1)
        r.Fail(dp + ".recordings", std::to_string(g.disparity_noise.recordings) +
                                       " recordings; a measured sigma_px has at least 1");
    }
    if (gn["cv"]) {
      const auto cv = r.Cv(gn["cv"], p + ".cv");
      if (cv.scheme != "none") g.cv.push_back(cv);
    }
    if (gn["cv_more"]) {
      const YAML::Node more = gn["cv_more"];
      if (!more.IsSequence()) r.Fail(p + ".cv_more", "expected a list");
      for (size_t k = 0; k < more.size(); ++k) {
        g.cv.push_back(r.Cv(more[k], p + ".cv_more[" + std::to_string(k) + "]"));
      }
    }
    if (gn["covariance"]) {
      const YAML::Node cn = gn["covariance"];
      if (!cn.IsSequence()) r.Fail(p + ".covariance", "expected a list of rows");
      for (size_t k = 0; k < cn.size(); ++k) {
        g.covariance.push_back(r.Doubles(cn[k], p + ".covariance[" + std::to_string(k) + "]"));
      }
      // An empty list is what the writer gives for an unknown covariance.
      if (!g.covariance.empty())
        CheckCovariance(r, g.covariance, g.values.size(), p + ".covariance");
    }
    w.groups.push_back(std::move(g));
  }
  if (const YAML::Node prov = root["provenance"]; prov) {
    if (!prov.IsMap()) r.Fail("provenance", "expected a map");
    r.OnlyKeys(prov, "provenance", {"input_file", "input_sha256", "tool", "tool_version"});
    if (prov["input_file"]) w.input_file = r.String(prov["input_file"], "provenance.input_file");
    if (prov["input_sha256"]) {
      w.input_sha256 = r.String(prov["input_sha256"], "provenance.input_sha256");
    }
    if (prov["tool"]) w.tool = r.String(prov["tool"], "provenance.tool");
    if (prov["tool_version"]) {
      w.tool_version = r.String(prov["tool_version"], "provenance.tool_version");
    }
  }
  return w;
}

records::BiasWeights ReadWeightsYaml(const std::string& path) {
  return ParseWeightsYaml(ReadFile(path, kMaxYamlBytes), path);
}

}  // namespace depthbias::io
