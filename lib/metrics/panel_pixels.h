#pragma once
// Which pixels of a panel's image region show the panel: the one decision, made from the pooled
// frames, that panel_extract and the simulator's metrics-only path both call, so that the region
// the metrics kernel measures is defined once.
//
// A region pixel is classified from its valid samples pooled over the first frames of the
// recording (count n and mean depth Z̄) against the panel's plane and the ground: on the plane,
// behind it (the background seen past the panel's edge), in front of it (an occluder), on the
// ground, or a hole (no sample). The panel's plane is fitted to the region's own pooled pixels in
// inverse depth (1/Z = k·(x/z, y/z, 1)), first on the region's interior (the central half of its
// bounding box each way), each observed pixel counted once (a textured background seen past the
// panel's edge has many samples a pixel where a hole-ridden panel has few), then refitted on the
// pixels found on it, each weighted by its samples, until they no longer change (at most
// refit_iterations times). The first plane is a least-squares one: a background strip with more
// observed pixels than the interior's still turns it. A pixel departs from the plane when its
// mean depth differs from the plane's depth on its ray by more than
// sigma_k·σ_Z(Z)/√n + plane_distance_m, σ_Z = Z²·σ_d/(f·B); σ_d is the larger of
// expected_subpixel_rms_px and the interior's own scatter (1.4826 × the median absolute disparity
// residual × √n of its pixels), so that the noise of a far, noisy recording is not mistaken for
// the background. The interior reads the noise because the pixels being judged are at the edges:
// a scatter read over the whole region counts them in it, and the decision had two answers.
// Simulated at 16 m (HA, a 3-pixel border mixing up to half of each sample with the background),
// it left the border's 263 pixels out at 16.00 m (scatter 0.09 px) and kept all but 17 of them
// at 16.02 m, whose first, wider scatter (0.48 px) they held up themselves: the tilt read 1.5° at
// one and 14.4° at the other, mean − median 0.07 and 0.65 m. Read on the interior, the border is
// left out at every distance from 15.90 to 16.10 m (tilt 0.5–3.6°). Fewer than 12 observed
// interior pixels, or a region without a bounding box: the whole region. The panel's pixels are
// the region's pixels that are holes or on the plane.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "camera/intrinsics.h"
#include "metrics/geometry.h"

namespace depthbias::metrics {

enum class PixelClass : std::uint8_t { kHole, kOnPlane, kBehind, kInFront, kGround };

struct PanelPixelParams {
  double baseline_m = camera::D455::kBaselineM;  // B [m]
  double expected_subpixel_rms_px = 0.08;        // σ_d floor [px]
  double sigma_k = 4.0;                          // departure threshold in σ of a pixel's mean
  double plane_distance_m = 0.02;                // added to the threshold [m]
  double ground_distance_m = 0.08;               // a sample this near the ground is the ground
  int refit_iterations = 3;                      // plane refitted on its own pixels, at most
  // Frames pooled for the decision: the first pooled_frames frames of the recording (0: all).
  int pooled_frames = 30;

  bool IsValid(std::string* why) const;
};

// One pixel's pooled frames: valid samples and their summed depth counts.
struct PooledPixel {
  std::uint32_t count = 0;
  std::uint64_t sum_counts = 0;
};

// Departure limit of a pixel's mean of n samples from the plane's depth zp [m].
double DepartureLimitM(double plane_depth_m, std::uint32_t n, double focal_px,
                       double subpixel_rms_px, const PanelPixelParams& params);

// Class of a pixel of mean depth mean_depth_m over n samples on ray (x/z, y/z, 1) against plane
// (and ground, which may be null), with disparity noise subpixel_rms_px.
PixelClass ClassifyMeanDepth(const Eigen::Vector3d& ray, std::uint32_t n, double mean_depth_m,
                             double focal_px, double subpixel_rms_px, const Plane& plane,
                             const Plane* ground, const PanelPixelParams& params);

struct PanelPixels {
  bool plane_ok = false;
  Plane plane;                        // the panel's plane fitted to the region's pooled pixels
  double subpixel_rms_px = 0.0;       // σ_d the classification used
  std::vector<std::uint32_t> pixels;  // the region's pixels showing the panel, sorted
  int on_plane = 0, holes = 0, behind = 0, in_front = 0, ground = 0;  // by class
  int excluded() const { return behind + in_front + ground; }
};

// The panel's pixels of region from pooled (one entry per region pixel, in region order, depth
// counts in depth_units_m). ground may be null. Without a plane (fewer than 3 observed pixels),
// every region pixel is kept.
PanelPixels DecidePanelPixels(const camera::Intrinsics& intrinsics, const PanelRegion& region,
                              const std::vector<PooledPixel>& pooled, double depth_units_m,
                              const Plane* ground, const PanelPixelParams& params);

// The plane 1/Z = k·(x/z, y/z, 1) of the given image pixels' pooled mean depths (pooled[k] of
// pixels[k]), each weighted by its samples (least squares for noise along the rays, as
// DecidePanelPixels refits it); false for fewer than 3 observed pixels or a degenerate system.
bool FitPooledPlane(const camera::Intrinsics& intrinsics, const std::vector<std::uint32_t>& pixels,
                    const std::vector<PooledPixel>& pooled, double depth_units_m, Plane* plane);

// The region reduced to the given sorted pixels (outline and bounding box kept).
PanelRegion WithPixels(const PanelRegion& region, std::vector<std::uint32_t> pixels);

}  // namespace depthbias::metrics
