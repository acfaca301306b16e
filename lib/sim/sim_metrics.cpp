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
  std::string region_why;
  if (!region.IsValid(&region_why)) {
    if (why) *why = "region: " + region_why;
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
  PixelList pixels = sim.RegionPixels(mp.region_margin_px, &region);
  if (pixels.empty()) {
    m.region_px = 0;
    m.status = "no_panel";
    m.message = "the panel's image region is empty";
    return result;
  }

  // The first pooled frames decide the panel's pixels, as panel_extract's pooled frames do; they
  // are kept and measured, the rest rendered on the decided pixels alone.
  const std::size_t n_px = pixels.size();
  const int pooled_frames =
      mp.region.pooled_frames > 0 ? std::min(mp.region.pooled_frames, frames) : frames;
  const bool decide = !(params.departures.region_spill_px > 0);
  std::vector<std::uint16_t> stored(decide ? static_cast<std::size_t>(pooled_frames) * n_px : 0);
  std::vector<std::uint16_t> counts;
  int rendered = 0;
  if (decide) {
    // 32-bit sums (vectorized), carried into 64-bit ones every 65535 frames of 16-bit counts.
    std::vector<std::uint32_t> n_valid(n_px, 0), sum(n_px, 0);
    std::vector<std::uint64_t> carry(n_px, 0);
    for (; rendered < pooled_frames; ++rendered) {
      if (rendered > 0 && rendered % 65535 == 0)
        for (std::size_t k = 0; k < n_px; ++k) {
          carry[k] += sum[k];
          sum[k] = 0;
        }
      std::uint16_t* frame = stored.data() + static_cast<std::size_t>(rendered) * n_px;
      sim.RenderPixels(rendered, pixels, &counts);
      std::copy(counts.begin(), counts.end(), frame);
      for (std::size_t k = 0; k < n_px; ++k) {
        n_valid[k] += frame[k] != 0;
        sum[k] += frame[k];
      }
    }
    std::vector<metrics::PooledPixel> pooled(n_px);
    for (std::size_t k = 0; k < n_px; ++k) pooled[k] = {n_valid[k], carry[k] + sum[k]};
    const Eigen::Matrix3d level = LevelFromCamera(params.protocol.scene);
    metrics::Plane ground;
    ground.normal = level.transpose() * Eigen::Vector3d(0, -1, 0);
    ground.offset_m = params.protocol.scene.camera_height_m;
    metrics::PanelPixels decided =
        metrics::DecidePanelPixels(in, region, pooled, s.depth_units_m, &ground, mp.region);
    if (decided.excluded() > 0) {
      // Keep the decided pixels' positions in the region, the stored frames and the pixel list.
      std::vector<std::size_t> keep;
      keep.reserve(decided.pixels.size());
      for (std::size_t k = 0, j = 0; k < n_px && j < decided.pixels.size(); ++k)
        if (region.pixels[k] == decided.pixels[j]) {
          keep.push_back(k);
          ++j;
        }
      PixelList kept;
      kept.window.reserve(keep.size());
      kept.image.reserve(keep.size());
      for (std::size_t k : keep) {
        kept.window.push_back(pixels.window[k]);
        kept.image.push_back(pixels.image[k]);
      }
      std::vector<std::uint16_t> kept_stored(static_cast<std::size_t>(pooled_frames) *
                                             keep.size());
      for (int f = 0; f < pooled_frames; ++f)
        for (std::size_t q = 0; q < keep.size(); ++q)
          kept_stored[f * keep.size() + q] = stored[f * n_px + keep[q]];
      pixels = std::move(kept);
      stored.swap(kept_stored);
      region.pixels.swap(decided.pixels);
    }
  }
  result.region_px = static_cast<int>(pixels.size());
  m.region_px = static_cast<double>(pixels.size());
  if (pixels.empty()) {
    m.status = "no_panel";
    m.message = "no pixel of the panel's region shows the panel";
    return result;
  }

  // The frames' region pixels go through the metrics kernel, as panel_extract's do.
  metrics::KernelParams kp;
  kp.baseline_m = s.baseline_m;
  kp.region_margin_px = mp.region_margin_px;
  metrics::RegionMetrics kernel(in, region, kp);
  for (int k = 0; k < rendered; ++k)
    kernel.AddRegionCounts(stored.data() + static_cast<std::size_t>(k) * pixels.size(),
                           s.depth_units_m);
  for (int k = rendered; k < frames; ++k) {
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
