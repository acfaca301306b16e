#pragma once
// The panel's rectangle fitted to a candidate plane with the panel's known size, and the
// evidence that scores the candidate as the panel.
//
// Every observed pixel near the plane is classified against it (PixelEvidence): on the plane,
// behind it (background seen where the panel would stand), in front of it, or on the ground. A
// window of the panel's known size slides over the plane (in plane coordinates, axes from the up
// direction) to the position that maximises  on − λ·(behind + ground) − μ·in front.
// A textureless panel loses most of its own pixels (holes), but the background around it keeps
// its depth: the window's edges are set by where the background shows, not by the panel's sparse
// pixels, and a coplanar post, stand or person beside it cannot stretch it. What lies on the plane
// outside the window is reported as cut off.
//
// The evidence also tells a panel from other planes of its size: a panel is solid (little
// background seen through its window) and stands free (little of the plane continues in a ring
// around it), where a bush lets the background through and is rough, a person is half as wide,
// and a wall or hedge continues beyond the window.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "metrics/geometry.h"
#include "metrics/panel_pixels.h"
#include "panel/detect.h"
#include "panel/params.h"

namespace depthbias::panel {

using metrics::PixelClass;

// Classifies one pixel of the accumulated image against the plane: depth residual against the
// noise of the pixel's mean (evidence_sigma_k·σ_Z(Z)/√n + plane_distance_m). ground may be null.
PixelClass ClassifyPixel(const metrics::RayTable& rays, const DepthAccumulator& acc,
                         std::uint32_t pixel, const metrics::Plane& plane,
                         const metrics::Plane* ground, const PanelParams& params);

struct WindowFit {
  bool success = false;
  std::string message;            // why not
  metrics::PanelRectangle rect;   // the panel's known size, on the plane
  WindowEvidence evidence;
  std::vector<std::uint32_t> on_plane_pixels;  // inside the window, for refitting the plane
};

// Fits the known-size window on plane around seed_m (a point of the candidate on the plane),
// searching panel-size·search_extent on each side.
WindowFit FitPanelWindow(const metrics::RayTable& rays, const DepthAccumulator& acc,
                         const metrics::Plane& plane, const Eigen::Vector3d& up_hint,
                         const metrics::Plane* ground, const Eigen::Vector3d& seed_m,
                         const PanelParams& params);

// The window fit refined: plane refitted on the window's on-plane pixels (each weighted by its
// sample count) and the window fitted again, refine_iterations times.
WindowFit FitAndRefinePanel(const metrics::RayTable& rays, const DepthAccumulator& acc,
                            metrics::Plane plane, const Eigen::Vector3d& up_hint,
                            const metrics::Plane* ground, const Eigen::Vector3d& seed_m,
                            const PanelParams& params, double* plane_rms_m);

// The one decision of the panel's pixels (metrics/panel_pixels.h) with the panel's parameters.
metrics::PanelPixelParams PanelPixelParamsOf(const PanelParams& params);

// The panel's pixels of region, decided from the accumulated frames by the same function as the
// simulator's metrics-only path (metrics::DecidePanelPixels). ground may be null.
metrics::PanelPixels DecideRegionPixels(const DepthAccumulator& acc,
                                        const camera::Intrinsics& intrinsics,
                                        const metrics::PanelRegion& region,
                                        const metrics::Plane* ground, const PanelParams& params);

}  // namespace depthbias::panel
