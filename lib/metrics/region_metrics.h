#pragma once
// The metrics kernel: DESIGN.md's panel-metrics columns of one recording from the depth counts of
// the panel's image region over its frames. The one implementation, used by panel_extract (real
// and simulated bags) and by the simulator's metrics-only path, so that a difference between the
// two is never an artefact of two definitions.
//
// Streaming: per region pixel a running count, ΣZ, ΣZ², Σ1/Z, Σ1/Z²; pooled histograms of depth
// counts and of range, so the medians are exact and memory does not grow with the frames.
//
// Definitions (every sample is a valid, non-zero depth count of a region pixel in one frame):
//   frames           frames with at least one valid sample in the region
//   mean_m, median_m mean and median depth Z of the samples pooled over frames (median: the mean
//                    of the two middle samples for an even count)
//   hole_rate_pct    100 · (1 − samples / (region pixels · frames)); valid_pct = 100 − hole_rate
//   plane_std_m      RMS orthogonal distance of the samples to their total-least-squares plane
//   normal_tilt_deg  angle between the optical axis and the normal of the plane fitted in inverse
//                    depth, 1/Z = a·x/z + b·y/z + c (ordinary least squares over the samples: the
//                    maximum-likelihood plane for disparity noise, no tilt bias at long range)
//   subpixel_rms_px  √mean((f·B/Z − f·B/Z_P)²) against that plane (the Depth Quality Tool's)
//   range_m          median of the samples' Euclidean ranges Z·|ray|
//   temporal_std_m   median over region pixels with ≥ 2 samples of each pixel's sample standard
//                    deviation over time (mean of the two middle values for an even count)
//   panel_width_m, panel_height_m, azimuth_deg, elevation_deg
//                    the rectangle spanned on the inverse-depth plane by the region pixels that
//                    had at least one sample (axes from the given up direction, pixel footprints
//                    added back for the region's margin), and the direction of its centre
//                    (azimuth + right, elevation + up)
//   region_px        pixels in the region
//   sigma_d_px       temporal disparity noise σ_d: Δd = f·B·(1/Z − 1/Z_prev) of every region
//                    pixel valid in two consecutive frames, σ_d = robust RMS(Δd)/√2
//                    (camera/disparity_noise.h, the estimator the obstacle detector uses at its
//                    obstacles); NaN with fewer than min_noise_pairs pairs

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "camera/disparity_noise.h"
#include "camera/intrinsics.h"
#include "metrics/geometry.h"
#include "records/depth_frame.h"
#include "records/panel_metrics.h"

namespace depthbias::metrics {

struct KernelParams {
  double baseline_m = camera::D455::kBaselineM;  // B, for the disparity-unit metrics [m]
  // The region's margin (pixel footprints a side, as drawn by RegionFromRectangle): added back
  // to the extent of the sampled pixels so the panel's size is not reported short.
  double region_margin_px = 0.5;
  // Fewer pixel pairs (valid in two consecutive frames) than this: sigma_d_px is not measured.
  int min_noise_pairs = 200;

  bool IsValid(std::string* why) const;
};

struct KernelResult {
  bool success = false;
  std::string message;          // why not, when !success
  PlaneFit plane;               // total-least-squares plane of every sample
  bool disparity_plane_ok = false;
  Plane disparity_plane;        // the inverse-depth plane (tilt, subpixel RMS)
  // Standard error of normal_tilt_deg from the inverse-depth fit's covariance (linearized): the
  // tilt a recording can resolve. Far, hole-ridden panels have a few degrees.
  double tilt_sigma_deg = records::PanelMetrics::kMissing;
  bool rectangle_ok = false;
  PanelRectangle rectangle;     // sampled pixels on the disparity plane
  std::uint64_t samples = 0;    // valid samples pooled over frames
  std::uint64_t frames = 0;     // frames added
  std::uint64_t frames_with_depth = 0;
  long long noise_pairs = 0;    // pixel pairs behind sigma_d_px
};

class RegionMetrics {
 public:
  // The region's pixels are deprojected once with the intrinsics. Throws std::invalid_argument
  // for invalid parameters or a region whose image size differs from the intrinsics'.
  RegionMetrics(const camera::Intrinsics& intrinsics, const PanelRegion& region,
                const KernelParams& params = {});

  // A whole image of the recording (its size must match the intrinsics; checked by the caller).
  void AddFrame(const records::DepthFrame& frame);
  // The depth counts of the region's pixels, in the region's order, of one frame.
  void AddRegionCounts(const std::uint16_t* counts, double depth_units_m);

  // Fills every measured column of metrics (the nominal ones — bag, light, distance … — are the
  // caller's); up_m is the scene's up direction in the camera frame (the panel's height axis).
  KernelResult Finish(const Eigen::Vector3d& up_m, records::PanelMetrics* metrics) const;

  std::size_t size() const { return pixels_.size(); }
  const std::vector<std::uint32_t>& pixels() const { return pixels_; }

 private:
  struct PixelSums {
    std::uint32_t n = 0;
    double z = 0, z2 = 0, inv = 0, inv2 = 0;
  };
  // What a sample of depth count c adds, computed once per count: z = c·units, z², 1/z, 1/z²,
  // and 1/c (sigma_d_px).
  struct CountTerms {
    double z = 0, z2 = 0, inv = 0, inv2 = 0, per_count = 0;
  };
  // Makes the count tables and histograms cover the counts [c_lo, c_hi] (c_lo >= 1) and the
  // ranges [r_lo, r_hi].
  void Cover(std::size_t c_lo, std::size_t c_hi, std::size_t r_lo, std::size_t r_hi);

  camera::Intrinsics intrinsics_;
  KernelParams params_;
  std::vector<std::uint32_t> pixels_;
  std::vector<Eigen::Vector3d> rays_;  // (x/z, y/z, 1) per region pixel
  std::vector<float> range_per_count_;  // |ray| per region pixel
  float min_range_per_count_ = 1.0f, max_range_per_count_ = 1.0f;
  std::vector<PixelSums> sums_;
  std::vector<std::uint16_t> gathered_;
  std::vector<std::uint16_t> previous_;  // the frame before's counts (sigma_d_px)
  std::vector<std::uint32_t> valid_, pairs_;  // scratch: a frame's valid pixels, valid pairs
  camera::TemporalNoise temporal_noise_;
  // Histograms over the values seen so far: depth_hist_[i] counts depth count
  // count_lo_ + i − 1, range_hist_[i] range (in depth units) range_lo_ + i − 1 ([0] unused).
  // terms_ is indexed as depth_hist_.
  std::size_t count_lo_ = 0, range_lo_ = 0;  // 0: nothing covered yet
  std::vector<CountTerms> terms_;
  std::vector<std::uint64_t> depth_hist_;
  std::vector<std::uint64_t> range_hist_;
  double depth_units_m_ = 0.0;
  std::uint64_t frames_ = 0;
  std::uint64_t frames_with_depth_ = 0;
  bool mixed_units_ = false;
};

}  // namespace depthbias::metrics
