#include "model/samples.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>

namespace depthbias::model {
namespace {

std::vector<double> Distinct(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  std::vector<double> out;
  for (double x : v) {
    if (out.empty() || std::abs(x - out.back()) > 1e-9) out.push_back(x);
  }
  return out;
}

}  // namespace

std::vector<Sample> MakeSamples(const std::vector<records::PanelMetrics>& rows,
                                const std::vector<size_t>& which, bool weight_by_valid_pixels) {
  std::vector<Sample> out;
  for (size_t i : which) {
    const auto& r = rows.at(i);
    Sample s;
    s.x.depth_m = r.median_m;
    // The model is even in α (domain.h): a row at −20° is a row at 20°.
    s.x.angle_rad = std::abs(r.angle_deg) * M_PI / 180.0;
    s.target_m = r.median_m - r.distance_m;
    s.distance_m = r.distance_m;
    s.angle_deg = std::abs(r.angle_deg);
    s.row = i;
    if (weight_by_valid_pixels) {
      const double region = std::isnan(r.region_px) ? 1.0 : r.region_px;
      const double frames = std::isnan(r.frames) ? 1.0 : r.frames;
      const double valid = std::isnan(r.valid_pct) ? 0.0 : r.valid_pct;
      s.weight = valid * region * frames;
    }
    out.push_back(s);
  }
  if (weight_by_valid_pixels && !out.empty()) {
    double mean = 0.0;
    for (const auto& s : out) mean += s.weight;
    mean /= static_cast<double>(out.size());
    for (auto& s : out) s.weight = mean > 0.0 ? s.weight / mean : 1.0;
  }
  return out;
}

std::string Group::Label() const {
  std::string label;
  for (const auto* v : {&light, &preset, &emitter}) {
    if (*v == "*") continue;
    label += (label.empty() ? "" : "/") + *v;
  }
  return label.empty() ? "all" : label;
}

std::vector<Group> GroupRows(const std::vector<records::PanelMetrics>& rows,
                             const std::vector<std::string>& group_by) {
  bool by_light = false, by_preset = false, by_emitter = false;
  for (const auto& k : group_by) {
    if (k == "light") by_light = true;
    else if (k == "preset") by_preset = true;
    else if (k == "emitter") by_emitter = true;
    else throw std::invalid_argument("unknown grouping key '" + k +
                                     "' (known: light, preset, emitter)");
  }
  std::map<std::tuple<std::string, std::string, std::string>, Group> groups;
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto& r = rows[i];
    if (!UsableForFit(r)) continue;
    const auto key = std::make_tuple(by_light ? r.light : "*", by_preset ? r.preset : "*",
                                     by_emitter ? r.emitter : "*");
    Group& g = groups[key];
    std::tie(g.light, g.preset, g.emitter) = key;
    g.rows.push_back(i);
  }
  std::vector<Group> out;
  for (auto& [key, g] : groups) out.push_back(std::move(g));
  return out;
}

std::vector<double> DistinctDistances(const std::vector<Sample>& samples) {
  std::vector<double> v;
  for (const auto& s : samples) v.push_back(s.distance_m);
  return Distinct(v);
}

std::vector<double> DistinctAngles(const std::vector<Sample>& samples) {
  std::vector<double> v;
  for (const auto& s : samples) v.push_back(s.angle_deg);
  return Distinct(v);
}

}  // namespace depthbias::model
