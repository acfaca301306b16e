#include "panel/params.h"

#include <cmath>
#include <cstdlib>
#include <functional>
#include <map>

namespace depthbias::panel {
namespace {

bool ParseDouble(const std::string& text, double* out) {
  if (text.empty()) return false;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

bool ParseBool(const std::string& text, bool* out) {
  if (text == "true" || text == "1" || text == "yes" || text == "on") {
    *out = true;
  } else if (text == "false" || text == "0" || text == "no" || text == "off") {
    *out = false;
  } else {
    return false;
  }
  return true;
}

using Setter = std::function<bool(PanelParams*, const std::string&)>;

Setter D(double PanelParams::*field) {
  return [field](PanelParams* p, const std::string& t) { return ParseDouble(t, &(p->*field)); };
}
Setter I(int PanelParams::*field) {
  return [field](PanelParams* p, const std::string& t) {
    double v;
    if (!ParseDouble(t, &v) || v != std::floor(v) || std::fabs(v) > 1e9) return false;
    p->*field = static_cast<int>(v);
    return true;
  };
}
Setter B(bool PanelParams::*field) {
  return [field](PanelParams* p, const std::string& t) { return ParseBool(t, &(p->*field)); };
}

const std::map<std::string, Setter>& Table() {
  static const std::map<std::string, Setter> table = {
      {"panel_width_m", D(&PanelParams::panel_width_m)},
      {"panel_height_m", D(&PanelParams::panel_height_m)},
      {"size_tolerance", D(&PanelParams::size_tolerance)},
      {"baseline_m", D(&PanelParams::baseline_m)},
      {"expected_subpixel_rms_px", D(&PanelParams::expected_subpixel_rms_px)},
      {"detection_frames", I(&PanelParams::detection_frames)},
      {"keep_detection_frames", B(&PanelParams::keep_detection_frames)},
      {"block_px", I(&PanelParams::block_px)},
      {"max_depth_m", D(&PanelParams::max_depth_m)},
      {"min_depth_m", D(&PanelParams::min_depth_m)},
      {"remove_ground", B(&PanelParams::remove_ground)},
      {"ground_distance_m", D(&PanelParams::ground_distance_m)},
      {"ground_max_angle_deg", D(&PanelParams::ground_max_angle_deg)},
      {"min_ground_fraction", D(&PanelParams::min_ground_fraction)},
      {"cluster_angle_rad", D(&PanelParams::cluster_angle_rad)},
      {"cluster_relative_depth", D(&PanelParams::cluster_relative_depth)},
      {"min_cluster_points", I(&PanelParams::min_cluster_points)},
      {"max_clusters", I(&PanelParams::max_clusters)},
      {"max_planes_per_cluster", I(&PanelParams::max_planes_per_cluster)},
      {"plane_sigma_k", D(&PanelParams::plane_sigma_k)},
      {"plane_distance_m", D(&PanelParams::plane_distance_m)},
      {"ransac_max_iterations", I(&PanelParams::ransac_max_iterations)},
      {"ransac_probability", D(&PanelParams::ransac_probability)},
      {"max_facing_angle_deg", D(&PanelParams::max_facing_angle_deg)},
      {"refine_iterations", I(&PanelParams::refine_iterations)},
      {"evidence_sigma_k", D(&PanelParams::evidence_sigma_k)},
      {"see_through_weight", D(&PanelParams::see_through_weight)},
      {"front_weight", D(&PanelParams::front_weight)},
      {"edge_weight", D(&PanelParams::edge_weight)},
      {"search_extent", D(&PanelParams::search_extent)},
      {"max_see_through", D(&PanelParams::max_see_through)},
      {"ring_width_frac", D(&PanelParams::ring_width_frac)},
      {"min_coverage", D(&PanelParams::min_coverage)},
      {"use_search_window", B(&PanelParams::use_search_window)},
      {"window_distance_frac", D(&PanelParams::window_distance_frac)},
      {"window_distance_m", D(&PanelParams::window_distance_m)},
      {"window_angle_deg", D(&PanelParams::window_angle_deg)},
      {"region_margin_px", D(&PanelParams::region_margin_px)},
      {"hole_fill",
       [](PanelParams* p, const std::string& t) {
         if (t != "opencv" && t != "sweeps") return false;
         p->hole_fill = t;
         return true;
       }},
      {"seed", [](PanelParams* p, const std::string& t) {
         double v;
         if (!ParseDouble(t, &v) || v < 0 || v != std::floor(v) || v > 1.8e19) return false;
         p->seed = static_cast<std::uint64_t>(v);
         return true;
       }},
  };
  return table;
}

}  // namespace

bool PanelParams::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(panel_width_m > 0) || !(panel_height_m > 0)) return fail("panel size must be positive");
  if (!(size_tolerance > 0 && size_tolerance < 1)) return fail("size_tolerance must be in (0, 1)");
  if (!(baseline_m > 0)) return fail("baseline_m must be positive");
  if (!(expected_subpixel_rms_px > 0)) return fail("expected_subpixel_rms_px must be positive");
  if (detection_frames < 0) return fail("detection_frames must be 0 (all) or positive");
  if (block_px < 0 || block_px > 64) return fail("block_px must be in 0..64");
  if (!(min_depth_m >= 0 && max_depth_m > min_depth_m))
    return fail("need 0 <= min_depth_m < max_depth_m");
  if (!(ground_distance_m > 0)) return fail("ground_distance_m must be positive");
  if (!(ground_max_angle_deg > 0 && ground_max_angle_deg < 90))
    return fail("ground_max_angle_deg must be in (0, 90)");
  if (!(min_ground_fraction >= 0 && min_ground_fraction < 1))
    return fail("min_ground_fraction must be in [0, 1)");
  if (!(cluster_angle_rad > 0) || !(cluster_relative_depth > 0))
    return fail("cluster tolerances must be positive");
  if (min_cluster_points < 3) return fail("min_cluster_points must be at least 3");
  if (max_clusters < 1 || max_planes_per_cluster < 1)
    return fail("max_clusters and max_planes_per_cluster must be at least 1");
  if (!(plane_sigma_k > 0) || !(plane_distance_m >= 0))
    return fail("plane_sigma_k must be positive and plane_distance_m not negative");
  if (ransac_max_iterations < 1) return fail("ransac_max_iterations must be at least 1");
  if (!(ransac_probability > 0 && ransac_probability < 1))
    return fail("ransac_probability must be in (0, 1)");
  if (!(max_facing_angle_deg > 0 && max_facing_angle_deg <= 90))
    return fail("max_facing_angle_deg must be in (0, 90]");
  if (refine_iterations < 1) return fail("refine_iterations must be at least 1");
  if (!(evidence_sigma_k > 0) || !(see_through_weight >= 0) || !(front_weight >= 0) ||
      !(edge_weight >= 0))
    return fail("evidence_sigma_k must be positive, the window weights not negative");
  if (!(search_extent >= 0.25 && search_extent <= 5))
    return fail("search_extent must be in [0.25, 5] panel sizes");
  if (!(max_see_through > 0 && max_see_through <= 1))
    return fail("max_see_through must be in (0, 1]");
  if (!(ring_width_frac > 0 && ring_width_frac <= 1)) return fail("ring_width_frac must be in (0, 1]");
  if (!(min_coverage >= 0 && min_coverage <= 1)) return fail("min_coverage must be in [0, 1]");
  if (!(window_distance_frac >= 0) || !(window_distance_m >= 0) || !(window_angle_deg > 0))
    return fail("search window sizes must not be negative");
  if (!(region_margin_px >= 0 && region_margin_px < 20))
    return fail("region_margin_px must be in [0, 20)");
  if (hole_fill != "opencv" && hole_fill != "sweeps")
    return fail("hole_fill must be opencv or sweeps");
  return true;
}

bool PanelParams::Set(const std::string& key, const std::string& value, std::string* why) {
  const auto it = Table().find(key);
  if (it == Table().end()) {
    if (why) *why = "unknown parameter '" + key + "'";
    return false;
  }
  if (!it->second(this, value)) {
    if (why) *why = "parameter '" + key + "': cannot use value '" + value + "'";
    return false;
  }
  return true;
}

std::vector<std::string> PanelParams::Keys() {
  std::vector<std::string> keys;
  for (const auto& [k, v] : Table()) keys.push_back(k);
  return keys;
}

}  // namespace depthbias::panel
