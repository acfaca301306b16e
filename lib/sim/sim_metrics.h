#pragma once
// The metrics-only path: DESIGN.md's panel-metrics row of each recording, from the sensor model
// evaluated on the panel's image region alone (no whole frames), measured by the one metrics
// kernel (metrics/region_metrics.h) that panel_extract uses. What the gap diagnostic calls many
// times.

#include <vector>

#include "metrics/panel_pixels.h"
#include "records/panel_metrics.h"
#include "sim/stereo_sim.h"

namespace depthbias::sim {

// Options of the metrics-only path.
// The region measured is decided as panel_extract decides it: the panel's known size laid on the
// plane the first frames measure (where panel_extract's window lies: its extent in the image
// follows the range error), shrunk by region_margin_px, less the pixels that the first `region.pooled_frames` frames show to be
// something else than the panel (metrics::DecidePanelPixels, with panel_extract's default
// parameters). Under the region_spill effect the region is drawn, not decided (by hand, or a
// detector's box with a margin): its pixels are all measured.
struct MetricsParams {
  double region_margin_px = 0.5;  // panel rectangle shrunk by this many pixel footprints a side
  metrics::PanelPixelParams region;  // the decision of the panel's pixels
  int frames = 0;            // 0: the protocol's
  int threads = 1;           // recordings evaluated in parallel (results do not depend on it)
  // The region decided and its frames rendered as ever, but only the valid share measured
  // (valid_pct, hole_rate_pct, region_px and frames, the kernel's values bit for bit; every other
  // metric left missing): what a caller that reads the valid share alone needs, without the
  // metrics kernel.
  bool valid_share_only = false;

  bool IsValid(std::string* why) const;
};

// One recording's metrics (DESIGN.md's panel-metrics row), evaluated on the panel's image
// footprint without rendering whole frames. bag = the recording's name + ".bag".
struct CellMetricsResult {
  records::PanelMetrics metrics;
  CellTruth truth;
  int region_px = 0;
  // The panel's known size laid on the plane the first frames measure, around the panel seen
  // (as panel_extract's window): the rectangle the region is drawn from.
  metrics::PanelRectangle window;
};
CellMetricsResult SimulateMetrics(const SimParams& params, const Cell& cell,
                                  const MetricsParams& metrics = {});

// The given recordings, in their order.
std::vector<CellMetricsResult> SimulateCellsMetrics(const SimParams& params,
                                                    const std::vector<Cell>& cells,
                                                    const MetricsParams& metrics = {});

// One recording simulated at several widths of the region_spill effect (params' own width, valid
// as ever, is not used): result w is SimulateMetrics' with departures.region_spill_px =
// spills_px[w] (each >= 0, else std::invalid_argument). The width moves the drawn region alone,
// so the sensor, the footprint's frames and the measured plane are made once for all of them.
std::vector<CellMetricsResult> SimulateMetricsSpills(const SimParams& params, const Cell& cell,
                                                     const MetricsParams& metrics,
                                                     const std::vector<double>& spills_px);
// The given recordings at each width: [w][i] is recording i at spills_px[w].
std::vector<std::vector<CellMetricsResult>> SimulateCellsMetricsSpills(
    const SimParams& params, const std::vector<Cell>& cells, const MetricsParams& metrics,
    const std::vector<double>& spills_px);

// The true panel of a recording as a rectangle on its plane (normal toward the camera).
metrics::PanelRectangle PanelRectangleOf(const PanelPose& pose);

// Every recording of the protocol, in MakeCells' order.
std::vector<CellMetricsResult> SimulateProtocolMetrics(const SimParams& params,
                                                       const MetricsParams& metrics = {});

}  // namespace depthbias::sim
