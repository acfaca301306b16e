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

// Range under-read (as a share of the panel's size) up to which the panel's window, laid on the
// measured plane, is rendered whole; beyond it the window is cut to the rendered pixels.
constexpr double kUnderReadCover = 0.10;

// The panel's image bounding box, padded by pad px (and kUnderReadCover) and clipped to the
// image; empty if the panel is not in front of the camera.
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
  // The panel's window laid on a plane measured nearer than the truth covers more than the
  // panel's footprint: the window takes in kUnderReadCover of the panel's size around it.
  pad += static_cast<int>(std::ceil(0.5 * kUnderReadCover * std::max(u_hi - u_lo, v_hi - v_lo)));
  const int u0 = std::max(0, static_cast<int>(std::floor(u_lo)) - pad);
  const int v0 = std::max(0, static_cast<int>(std::floor(v_lo)) - pad);
  const int u1 = std::min(in.width, static_cast<int>(std::ceil(u_hi)) + pad + 1);
  const int v1 = std::min(in.height, static_cast<int>(std::ceil(v_hi)) + pad + 1);
  if (u1 <= u0 || v1 <= v0) return Window{};
  return Window{u0, v0, u1 - u0, v1 - v0};
}

// The panel's known size (true_rect's) at the depth the measured plane gives the panel's centre:
// the true rectangle moved along the rays by the ratio of that depth to the true one, its size
// kept. panel_extract's window is the panel's known size on its measured plane, placed on the
// panel it sees, so its extent in the image follows the range error (fewer pixels when
// over-read, the background around the panel taken in when under-read). The orientation is the
// true one: a plane measured on a far, noisy panel may turn by degrees about its centre, which
// panel_extract's RANSAC over the whole scene does not follow. rect unchanged when the plane
// misses the centre's ray.
void WindowOnPlane(const metrics::Plane& plane, const metrics::PanelRectangle& true_rect,
                   metrics::PanelRectangle* rect) {
  const Eigen::Vector3d ray = true_rect.center_m / true_rect.center_m.z();
  const double z = plane.DepthOnRay(ray);
  if (!std::isfinite(z) || !(z > 0)) return;
  const double scale = z / true_rect.center_m.z();
  metrics::PanelRectangle r = true_rect;
  r.center_m = scale * true_rect.center_m;
  r.plane.offset_m = scale * true_rect.plane.offset_m;
  *rect = r;
}

// Depth counts of `frames` frames of pixels, frame after frame.
void RenderFrames(const StereoSim& sim, const PixelList& pixels, int frames,
                  std::vector<std::uint16_t>* out) {
  const std::size_t n = pixels.size();
  out->resize(static_cast<std::size_t>(frames) * n);
  for (int f = 0; f < frames; ++f)
    sim.RenderPixels(f, pixels, out->data() + static_cast<std::size_t>(f) * n);
}

// The same for image pixels `image` (sorted; their list `pixels`), taking the counts of those
// already rendered in `known_frames` (of the sorted image pixels `known`) rather than rendering
// them again: a pixel's draw depends on the pixel and the frame alone.
void RenderFramesReusing(const StereoSim& sim, const std::vector<std::uint32_t>& image,
                         const PixelList& pixels, const std::vector<std::uint32_t>& known,
                         const std::vector<std::uint16_t>& known_frames, int frames,
                         std::vector<std::uint16_t>* out) {
  const std::size_t n = image.size(), n_known = known.size();
  // Runs of pixels in both lists: row[at + q] = known_row[from + q] for q < length.
  struct Run {
    std::size_t at, from, length;
  };
  std::vector<Run> runs;
  PixelList missing;
  std::vector<std::size_t> missing_at;
  for (std::size_t k = 0, j = 0; k < n; ++k) {
    while (j < n_known && known[j] < image[k]) ++j;
    if (j < n_known && known[j] == image[k]) {
      if (!runs.empty() && runs.back().at + runs.back().length == k &&
          runs.back().from + runs.back().length == j)
        ++runs.back().length;
      else
        runs.push_back({k, j, 1});
    } else {
      missing.window.push_back(pixels.window[k]);
      missing.image.push_back(pixels.image[k]);
      missing_at.push_back(k);
    }
  }
  out->resize(static_cast<std::size_t>(frames) * n);
  std::vector<std::uint16_t> counts;
  for (int f = 0; f < frames; ++f) {
    std::uint16_t* row = out->data() + static_cast<std::size_t>(f) * n;
    const std::uint16_t* known_row = known_frames.data() + static_cast<std::size_t>(f) * n_known;
    for (const Run& r : runs) std::copy_n(known_row + r.from, r.length, row + r.at);
    if (missing.empty()) continue;
    sim.RenderPixels(f, missing, &counts);
    for (std::size_t q = 0; q < missing_at.size(); ++q) row[missing_at[q]] = counts[q];
  }
}

// Each pixel's valid samples and summed counts over the frames (n pixels a frame).
std::vector<metrics::PooledPixel> Pool(const std::vector<std::uint16_t>& frames_counts,
                                       std::size_t n) {
  // 32-bit sums (vectorized), carried into 64-bit ones every 65535 frames of 16-bit counts.
  std::vector<std::uint32_t> n_valid(n, 0), sum(n, 0);
  std::vector<std::uint64_t> carry(n, 0);
  const std::size_t frames = n == 0 ? 0 : frames_counts.size() / n;
  for (std::size_t f = 0; f < frames; ++f) {
    if (f > 0 && f % 65535 == 0)
      for (std::size_t k = 0; k < n; ++k) {
        carry[k] += sum[k];
        sum[k] = 0;
      }
    const std::uint16_t* frame = frames_counts.data() + f * n;
    for (std::size_t k = 0; k < n; ++k) {
      n_valid[k] += frame[k] != 0;
      sum[k] += frame[k];
    }
  }
  std::vector<metrics::PooledPixel> pooled(n);
  for (std::size_t k = 0; k < n; ++k) pooled[k] = {n_valid[k], carry[k] + sum[k]};
  return pooled;
}

// The region drawn on result->window (grown by spill_px: region_spill), its frames (the
// footprint's reused), the pixels its pooled frames decide (a drawn region, spill_px > 0, is not
// decided) and the kernel's metrics of them, into *result.
void MeasureRegion(const StereoSim& sim, const MetricsParams& mp, int frames, int pooled_frames,
                   const metrics::Plane& ground, const metrics::PanelRegion& footprint,
                   const std::vector<std::uint16_t>& footprint_frames, double spill_px,
                   CellMetricsResult* result) {
  const SensorParams& s = sim.params().sensor;
  const auto& in = s.intrinsics;
  records::PanelMetrics& m = result->metrics;
  metrics::PanelRegion region;
  PixelList pixels = sim.RegionPixels(mp.region_margin_px, &region, &result->window, spill_px);
  if (pixels.empty()) {
    m.region_px = 0;
    m.status = "no_panel";
    m.message = "the panel's image region is empty";
    return;
  }
  std::vector<std::uint16_t> stored;
  RenderFramesReusing(sim, region.pixels, pixels, footprint.pixels, footprint_frames,
                      pooled_frames, &stored);
  if (!(spill_px > 0)) {  // a drawn region is not decided
    const std::size_t n_px = pixels.size();
    metrics::PanelPixels decided = metrics::DecidePanelPixels(
        in, region, Pool(stored, n_px), s.depth_units_m, &ground, mp.region);
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
  result->region_px = static_cast<int>(pixels.size());
  m.region_px = static_cast<double>(pixels.size());
  if (pixels.empty()) {
    m.status = "no_panel";
    m.message = "no pixel of the panel's region shows the panel";
    return;
  }

  if (mp.valid_share_only) {
    // The kernel's valid share (RegionMetrics::Finish): the valid samples over the region's
    // pixels times the frames; no valid sample is no panel.
    std::uint64_t samples = 0;
    std::size_t frames_with_depth = 0;
    auto add = [&](const std::uint16_t* frame) {
      std::uint64_t valid = 0;
      for (std::size_t q = 0; q < pixels.size(); ++q) valid += frame[q] != 0;
      samples += valid;
      frames_with_depth += valid > 0;
    };
    for (int k = 0; k < pooled_frames; ++k)
      add(stored.data() + static_cast<std::size_t>(k) * pixels.size());
    std::vector<std::uint16_t> counts;
    for (int k = pooled_frames; k < frames; ++k) {
      sim.RenderPixels(k, pixels, &counts);
      add(counts.data());
    }
    m.frames = static_cast<double>(frames_with_depth);
    m.valid_pct = 100.0 * static_cast<double>(samples) /
                  (static_cast<double>(pixels.size()) * static_cast<double>(frames));
    m.hole_rate_pct = 100.0 - m.valid_pct;
    if (samples == 0) {
      m.status = "no_panel";
      m.message = "no valid depth in the panel region";
    }
    return;
  }

  // The frames' region pixels go through the metrics kernel, as panel_extract's do.
  metrics::KernelParams kp;
  kp.baseline_m = s.baseline_m;
  kp.region_margin_px = mp.region_margin_px;
  metrics::RegionMetrics kernel(in, region, kp);
  std::vector<std::uint16_t> counts;
  for (int k = 0; k < pooled_frames; ++k)
    kernel.AddRegionCounts(stored.data() + static_cast<std::size_t>(k) * pixels.size(),
                           s.depth_units_m);
  for (int k = pooled_frames; k < frames; ++k) {
    sim.RenderPixels(k, pixels, &counts);
    kernel.AddRegionCounts(counts.data(), s.depth_units_m);
  }
  const metrics::KernelResult measured = kernel.Finish(-result->truth.panel.axis_height, &m);
  if (!measured.success) {
    m.status = "no_panel";
    m.message = measured.message;
    return;
  }
  if (!result->truth.scenario_listed)
    m.message = "scenario " + result->metrics.light + "/" + result->metrics.preset +
                " not in the sensor table: fallback noise and invalidation used";
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

std::vector<CellMetricsResult> SimulateMetricsSpills(const SimParams& params, const Cell& cell,
                                                     const MetricsParams& mp,
                                                     const std::vector<double>& spills_px) {
  std::string why;
  if (!mp.IsValid(&why)) throw std::invalid_argument("metrics parameters: " + why);
  if (!params.IsValid(&why)) throw std::invalid_argument("simulation parameters: " + why);
  for (double spill : spills_px)
    if (!(spill >= 0)) throw std::invalid_argument("region spill widths must be >= 0");
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
  // Every width alike, until the region is drawn.
  auto all = [&]() { return std::vector<CellMetricsResult>(spills_px.size(), result); };

  // The window holds every pixel whose static maps the region's pixels depend on, and the
  // pixels the panel's window takes in when the range is under-read (kUnderReadCover).
  const int pad =
      std::max(s.edge_band_px, static_cast<int>(params.departures.edge_mix_width_px)) + 3;
  const Window window = PanelWindow(params, cell, pad);
  if (window.width == 0) {
    m.status = "no_panel";
    m.message = "the panel is not in front of the camera";
    return all();
  }
  const StereoSim sim(params, cell, window);
  result.truth = sim.truth();
  const int pooled_frames =
      mp.region.pooled_frames > 0 ? std::min(mp.region.pooled_frames, frames) : frames;
  const Eigen::Matrix3d level = LevelFromCamera(params.protocol.scene);
  metrics::Plane ground;
  ground.normal = level.transpose() * Eigen::Vector3d(0, -1, 0);
  ground.offset_m = params.protocol.scene.camera_height_m;

  // The panel's plane as the first frames measure it, on the panel's true footprint less a band
  // of its edges' width (the sensor's edge band, the matching window's mixing): panel_extract's
  // plane is a robust one (RANSAC, refitted on pixels within the sensor's noise of it), which
  // pixels mixed with the background behind the panel's outline do not pull.
  const metrics::PanelRectangle true_rect = PanelRectangleOf(result.truth.panel);
  metrics::PanelRegion footprint;
  const PixelList footprint_px = sim.RectanglePixels(true_rect, mp.region_margin_px, &footprint);
  auto no_panel = [](CellMetricsResult* r) {
    r->metrics.region_px = 0;
    r->metrics.status = "no_panel";
    r->metrics.message = "the panel's image region is empty";
  };
  if (footprint_px.empty()) {
    no_panel(&result);
    return all();
  }
  std::vector<std::uint16_t> footprint_frames;
  RenderFrames(sim, footprint_px, pooled_frames, &footprint_frames);
  const std::vector<metrics::PooledPixel> footprint_pooled =
      Pool(footprint_frames, footprint_px.size());
  const int edge_px =
      std::max(s.edge_band_px, static_cast<int>(std::ceil(params.departures.edge_mix_width_px)));
  metrics::PanelRegion interior;
  sim.RectanglePixels(true_rect, mp.region_margin_px + edge_px, &interior);
  std::vector<metrics::PooledPixel> interior_pooled;
  {
    std::vector<std::uint32_t> kept;  // the interior's pixels, all within the footprint
    for (std::size_t k = 0, j = 0; k < interior.pixels.size(); ++k) {
      while (j < footprint.pixels.size() && footprint.pixels[j] < interior.pixels[k]) ++j;
      if (j == footprint.pixels.size() || footprint.pixels[j] != interior.pixels[k]) continue;
      kept.push_back(interior.pixels[k]);
      interior_pooled.push_back(footprint_pooled[j]);
    }
    interior.pixels.swap(kept);
  }
  constexpr std::size_t kMinInteriorPx = 25;  // fewer: the whole footprint measures the plane
  const bool use_interior = interior.pixels.size() >= kMinInteriorPx;
  metrics::Plane measured_plane;
  const bool plane_ok = metrics::FitPooledPlane(
      in, use_interior ? interior.pixels : footprint.pixels,
      use_interior ? interior_pooled : footprint_pooled, s.depth_units_m, &measured_plane);

  // The region: the panel's known size laid on that plane around the panel's seen centre, as
  // panel_extract lays its window (panel/panel_fit.h); its pooled frames decide its pixels.
  metrics::PanelRectangle rect = true_rect;
  if (plane_ok) WindowOnPlane(measured_plane, true_rect, &rect);
  result.window = rect;
  std::vector<CellMetricsResult> out = all();
  for (std::size_t w = 0; w < spills_px.size(); ++w)
    MeasureRegion(sim, mp, frames, pooled_frames, ground, footprint, footprint_frames,
                  spills_px[w], &out[w]);
  return out;
}

CellMetricsResult SimulateMetrics(const SimParams& params, const Cell& cell,
                                  const MetricsParams& mp) {
  return SimulateMetricsSpills(params, cell, mp, {params.departures.region_spill_px})[0];
}

std::vector<CellMetricsResult> SimulateCellsMetrics(const SimParams& params,
                                                    const std::vector<Cell>& cells,
                                                    const MetricsParams& metrics) {
  std::vector<CellMetricsResult> out(cells.size());
  common::ForEachIndex(cells.size(), metrics.threads,
                       [&](size_t i) { out[i] = SimulateMetrics(params, cells[i], metrics); });
  return out;
}

std::vector<std::vector<CellMetricsResult>> SimulateCellsMetricsSpills(
    const SimParams& params, const std::vector<Cell>& cells, const MetricsParams& metrics,
    const std::vector<double>& spills_px) {
  std::vector<std::vector<CellMetricsResult>> by_cell(cells.size());
  common::ForEachIndex(cells.size(), metrics.threads, [&](size_t i) {
    by_cell[i] = SimulateMetricsSpills(params, cells[i], metrics, spills_px);
  });
  std::vector<std::vector<CellMetricsResult>> out(spills_px.size(),
                                                  std::vector<CellMetricsResult>(cells.size()));
  for (std::size_t i = 0; i < cells.size(); ++i)
    for (std::size_t w = 0; w < spills_px.size(); ++w) out[w][i] = std::move(by_cell[i][w]);
  return out;
}

std::vector<CellMetricsResult> SimulateProtocolMetrics(const SimParams& params,
                                                       const MetricsParams& metrics) {
  return SimulateCellsMetrics(params, MakeCells(params.protocol), metrics);
}

}  // namespace depthbias::sim
