#pragma once
// The per-recording record of the panel-metrics CSV (DESIGN.md): what panel_extract measures of
// one recording, what the simulator's metrics-only path predicts, what fit_bias and the gap
// diagnostic read. A plain value type shared by every module; io reads and writes it as CSV.

#include <cmath>
#include <limits>
#include <string>

namespace depthbias::records {

struct PanelMetrics {
  static constexpr double kMissing = std::numeric_limits<double>::quiet_NaN();

  // The article's twelve columns.
  std::string bag;      // file name, or an id for rows without a recording
  std::string light;    // "daylight" / "sunset" / free text
  std::string emitter;  // "on" / "off"
  std::string preset;   // "HA" / "HD" / other preset name
  double distance_m = kMissing;  // nominal distance of the test point (ground truth)
  double angle_deg = kMissing;   // nominal off-axis position of the panel
  double frames = kMissing;      // frames with at least one valid pixel in the panel region
  double mean_m = kMissing;      // mean depth Z of valid region pixels, pooled over frames
  double median_m = kMissing;    // median depth Z of the same pixels
  double plane_std_m = kMissing; // RMS orthogonal distance of those points to their plane
  double hole_rate_pct = kMissing;  // zero-depth share of the region's pixels over all frames
  double valid_pct = kMissing;      // 100 − hole_rate_pct

  // Extra columns (empty for the article's rows).
  double range_m = kMissing;          // measured median range of the panel centre
  double azimuth_deg = kMissing;      // direction of the panel centre, + right
  double elevation_deg = kMissing;    // direction of the panel centre, + up
  double normal_tilt_deg = kMissing;  // fitted panel normal vs optical axis
  double panel_width_m = kMissing;
  double panel_height_m = kMissing;
  double region_px = kMissing;        // pixels in the panel's image region
  double subpixel_rms_px = kMissing;  // plane residuals in disparity units (Depth Quality Tool)
  double temporal_std_m = kMissing;   // median over region pixels of per-pixel std over time
  // Temporal disparity noise σ_d of the panel region: robust RMS of the disparity change of a
  // pixel between consecutive frames, / √2 (NaN: not measured, e.g. the article's rows).
  double sigma_d_px = kMissing;

  std::string status = "ok";  // "ok", "no_panel", "error", ...
  std::string message;

  bool ok() const { return status == "ok"; }
};

}  // namespace depthbias::records
