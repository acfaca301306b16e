#pragma once
// A candidate's surface along a continuous parameter, in the metrics the region's window decides
// (mean − median, tilt, width, the plane's spread: MetricInfo::window), as smooth as its
// simulations' own scatter allows. Each node of a candidate's grid is a simulation of its own,
// and those metrics take a fresh draw of the window's steps at every node: the window is the
// panel's known size laid on the measured plane, so its width in whole pixels follows the
// measured depth in steps (panel_width_m jumps by ±2 % from one offset node to the next at
// 16 m), the plane fit's tilt at 16 m scatters by about a degree between nodes, and plane_std
// there stands 5 % above its Z² law once the region has grown by a pixel on each side. A fit
// that interpolated through those draws would follow them along the parameter as if they were
// the effect's: on a user's unit of 32 rows with a −0.25 px offset, all seven metrics fitted
// −0.187 and −0.157 px at seeds 2 and 3 where the median alone reads −0.235 and −0.270. A
// camera's own window steps with its measured depth too, but at a placement no table knows, so
// what a model can predict of them is their trend. The other metrics (median, temporal spread,
// valid share) respond to an effect far beyond that scatter and keep their nodes. With the
// plane's spread kept at its nodes too, an offset of 0.15 px beside a drift was read 0.17–0.21
// px over seeds 1–5 of the withheld suite (within 20 % at 2 of 5); smoothed, 0.12–0.19 (4 of 5).
//
// The scatter of one node: every interior node of a continuous axis against the line through
// its two neighbours (variance σ²·(1 + w₁² + w₂²)), robust (1.4826 · median |r|) per candidate
// and metric, in the metric's noise shape (design.h), with the metric's quantization (a window
// one pixel wider or narrower) in quadrature. Each row of a surface along a continuous axis is
// then the penalized smooth (second divided differences) whose strength minimizes the unbiased
// risk estimate at that scatter: where the response is larger than the scatter, the smooth keeps
// the nodes; where it is a draw, it takes the trend. The neutral node stays the base, so that a
// candidate at its neutral value is the calibrated base.

#include <vector>

#include "gap/design.h"
#include "gap/simulations.h"

namespace depthbias::gap {

// Per compared metric: the scatter of one node of this surface at Z = 10 m, in its unit (0 where
// the metric is not a window's or the surface has too few interior nodes along a continuous axis).
std::vector<double> NodeScatter(const Design& design, const Surface& surface,
                                const Simulations& sims);

// Smooths y[0..n) given at ascending x with noise sigma per node; y[pinned] is kept (−1: none).
// Fewer than four nodes, or sigma ≤ 0: unchanged.
void SmoothAlong(const double* x, double* y, int n, int pinned, double sigma);

// Every candidate's surface smoothed along its continuous axes with its own NodeScatter, in the
// window's metrics.
void SmoothSurfaces(const Design& design, Simulations* sims);

// A range law's surface (Candidate::range_law) with its window metrics averaged over where the
// panel may stand. A range law moves the window only through the measured depth, and the window's
// whole pixels follow the measured depth as a sawtooth of period about Z²/(f·size) (one pixel of
// the panel's width: 2.5 % of the distance at 16 m). A surface simulated at the nominal distance
// reads that sawtooth at one phase; a camera's panel, placed off by the test point's placement
// scatter, reads it at another, and a table of placed panels shows its mean. On a user's unit of
// 32 rows with a −0.25 px offset, the nominal surface read the width 1.2–1.5 % wider at 16 m,
// the same table with its panels at their nominal distances 1.5 % wider, and with them placed
// (2 % of distance) 0.4 % narrower; the fit took the nominal phase as the offset's and read
// −0.13 to −0.20 px. Each node is the Gaussian mean over the line's nodes in measured depth
// (distance + the node's median bias), of width rel_of_cell[c] × that depth; the neutral node
// keeps its value. Other candidates and metrics are returned as they are, the plane's spread
// too: it follows a range law through the depth itself (∝ Z′²), and averaged over placement as
// well, the article's rows reported an offset and a scale detectable from −0.433 px and +7.1 %
// that they then did not keep at 1.5 times those sizes (docs/gap/cases.md).
Surface AverageOverPlacement(const Design& design, const Simulations& sims,
                             const Surface& surface, const std::vector<double>& rel_of_cell);

}  // namespace depthbias::gap
