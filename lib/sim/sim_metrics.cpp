// The metrics-only path: DESIGN.md's panel metrics of one recording, from the sensor model
// evaluated on the panel's image region alone, measured by the same kernel as panel_extract
// (metrics/region_metrics.h).

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "metrics/region_metrics.h"
#include "common/parallel.h"
#include "sim/sim_metrics.h"

namespace depthbias::sim {
namespace {

// The panel's image bounding box, padded by pad px and clipped to the image; empty if the panel
// is not in front of the camera.
Window PanelWindow(const SimParams& params, const Cell& cell, int pad) {
  const PanelPose pose = PlacePanel(params.protocol.scene, params.protocol.distance_is, cell,
                                    params.departures.range_vs_depth_weight,
                                    params.departures.panel_yaw_deg);
  const auto& in = params.sensor.intrinsics;
  double u_lo = 1e18, u_hi = -1e18, v_lo = 1e18, v_hi = -1e18;
  for (int sw : {-1, 1})
    for (int sh : {-1, 1}) {
      const Eigen::Vector3d c = pose.center_m + 0.5 * sw * pose.width_m * pose.axis_width +
                                0.5 * sh * pose.height_m * pose.axis_height;
      if (c.z() <= 1e-6) return Window{};
      const double u = in.ppx + in.fx * c.x() / c.z();
      const double v = in.ppy + in.fy * c.y() / c.z();
      u_lo = std::min(u_lo, u);
      u_hi = std::max(u_hi, u);
      v_lo = std::min(v_lo, v);
      v_hi = std::max(v_hi, v);
    }
  const int u0 = std::max(0, static_cast<int>(std::floor(u_lo)) - pad);
  const int v0 = std::max(0, static_cast<int>(std::floor(v_lo)) - pad);
  const int u1 = std::min(in.width, static_cast<int>(std::ceil(u_hi)) + pad + 1);
  const int v1 = std::min(in.height, static_cast<int>(std::ceil(v_hi)) + pad + 1);
  if (u1 <= u0 || v1 <= v0) return Window{};
  return Window{u0, v0, u1 - u0, v1 - v0};
}

}  // namespace

bool MetricsParams::IsValid(std::string* why) const {
  if (!(region_margin_px >= 0 && region_margin_px <= 100)) {
    if (why) *why = "region_margin_px must be in [0, 100]";
    return false;
  }
  if (frames < 0) {
    if (why) *why = "frames must be >= 0";
    return false;
  }
  if (threads < 1 || threads > 256) {
    if (why) *why = "threads must be in [1, 256]";
    return false;
  }
  return true;
}

CellMetricsResult SimulateMetrics(const SimParams& params, const Cell& cell,
                                  const MetricsParams& mp) {
  std::string why;
  if (!mp.IsValid(&why)) throw std::invalid_argument("metrics parameters: " + why);
  if (!params.IsValid(&why)) throw std::invalid_argument("simulation parameters: " + why);
  const SensorParams& s = params.sensor;
  const auto& in = s.intrinsics;
  const int frames = mp.frames > 0 ? mp.frames : params.protocol.frames;

  CellMetricsResult result;
  records::PanelMetrics& m = result.metrics;
  m.bag = cell.name + ".bag";
  m.light = cell.light;
  m.emitter = cell.emitter_on ? "on" : "off";
  m.preset = cell.preset;
  m.distance_m = cell.distance_m;
  m.angle_deg = cell.angle_deg;

  // The window holds every pixel whose static maps the region's pixels depend on.
  const int pad =
      std::max(s.edge_band_px, static_cast<int>(params.departures.edge_mix_width_px)) + 3;
  const Window window = PanelWindow(params, cell, pad);
  if (window.width == 0) {
    m.status = "no_panel";
    m.message = "the panel is not in front of the camera";
    return result;
  }
  const StereoSim sim(params, cell, window);
  result.truth = sim.truth();
  metrics::PanelRegion region;
  const PixelList pixels = sim.RegionPixels(mp.region_margin_px, &region);
  result.region_px = static_cast<int>(pixels.size());
  m.region_px = static_cast<double>(pixels.size());
  if (pixels.empty()) {
    m.status = "no_panel";
    m.message = "the panel's image region is empty";
    return result;
  }

  // The frames' region pixels go through the metrics kernel, as panel_extract's do.
  metrics::KernelParams kp;
  kp.baseline_m = s.baseline_m;
  kp.region_margin_px = mp.region_margin_px;
  metrics::RegionMetrics kernel(in, region, kp);
  std::vector<std::uint16_t> counts;
  for (int k = 0; k < frames; ++k) {
    sim.RenderPixels(k, pixels, &counts);
    kernel.AddRegionCounts(counts.data(), s.depth_units_m);
  }
  const metrics::KernelResult measured = kernel.Finish(-result.truth.panel.axis_height, &m);
  if (!measured.success) {
    m.status = "no_panel";
    m.message = measured.message;
    return result;
  }
  if (!result.truth.scenario_listed)
    m.message = "scenario " + cell.light + "/" + cell.preset + " not in the sensor table: "
                "fallback noise and invalidation used";
  return result;
}

std::vector<CellMetricsResult> SimulateCellsMetrics(const SimParams& params,
                                                    const std::vector<Cell>& cells,
                                                    const MetricsParams& metrics) {
  std::vector<CellMetricsResult> out(cells.size());
  common::ForEachIndex(cells.size(), metrics.threads,
                       [&](size_t i) { out[i] = SimulateMetrics(params, cells[i], metrics); });
  return out;
}

std::vector<CellMetricsResult> SimulateProtocolMetrics(const SimParams& params,
                                                       const MetricsParams& metrics) {
  return SimulateCellsMetrics(params, MakeCells(params.protocol), metrics);
}

}  // namespace depthbias::sim
