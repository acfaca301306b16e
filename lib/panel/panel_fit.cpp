#include "panel/panel_fit.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "camera/intrinsics.h"
#include "panel/hole_fill.h"

namespace depthbias::panel {
namespace {

// Grid of cells over the searched part of the plane, one count per class, with prefix sums.
class EvidenceGrid {
 public:
  enum Channel { kOn = 0, kNegative, kFront, kObserved, kChannels };
  EvidenceGrid(int ns, int nt) : ns_(ns), nt_(nt), cells_(kChannels * ns * nt, 0) {}
  void Add(int i, int j, PixelClass c) {
    int* cell = &cells_[kChannels * (j * ns_ + i)];
    ++cell[kObserved];
    if (c == PixelClass::kOnPlane) ++cell[kOn];
    if (c == PixelClass::kBehind || c == PixelClass::kGround) ++cell[kNegative];
    if (c == PixelClass::kInFront) ++cell[kFront];
  }
  int Cell(int i, int j, Channel ch) const { return cells_[kChannels * (j * ns_ + i) + ch]; }
  void Integrate() {
    sums_.assign(static_cast<std::size_t>(kChannels) * (ns_ + 1) * (nt_ + 1), 0);
    for (int j = 0; j < nt_; ++j)
      for (int i = 0; i < ns_; ++i)
        for (int ch = 0; ch < kChannels; ++ch)
          Sum(i + 1, j + 1, ch) = Cell(i, j, static_cast<Channel>(ch)) + Sum(i, j + 1, ch) +
                                  Sum(i + 1, j, ch) - Sum(i, j, ch);
  }
  // Total of cells [i0, i1) × [j0, j1), clipped to the grid.
  long Box(int i0, int j0, int i1, int j1, Channel ch) const {
    i0 = std::clamp(i0, 0, ns_);
    i1 = std::clamp(i1, 0, ns_);
    j0 = std::clamp(j0, 0, nt_);
    j1 = std::clamp(j1, 0, nt_);
    if (i1 <= i0 || j1 <= j0) return 0;
    return SumAt(i1, j1, ch) - SumAt(i0, j1, ch) - SumAt(i1, j0, ch) + SumAt(i0, j0, ch);
  }
  int ns() const { return ns_; }
  int nt() const { return nt_; }

 private:
  long& Sum(int i, int j, int ch) {
    return sums_[static_cast<std::size_t>(kChannels) * (j * (ns_ + 1) + i) + ch];
  }
  long SumAt(int i, int j, int ch) const {
    return sums_[static_cast<std::size_t>(kChannels) * (j * (ns_ + 1) + i) + ch];
  }
  int ns_, nt_;
  std::vector<int> cells_;
  std::vector<long> sums_;
};

struct Observed {
  std::uint32_t pixel;
  int cell_i, cell_j;
  PixelClass cls;
};

}  // namespace

PixelClass ClassifyPixel(const metrics::RayTable& rays, const DepthAccumulator& acc,
                         std::uint32_t pixel, const metrics::Plane& plane,
                         const metrics::Plane* ground, const PanelParams& p) {
  const std::uint32_t n = acc.Count(pixel);
  if (n == 0) return PixelClass::kHole;
  return metrics::ClassifyMeanDepth(rays.Ray(pixel), n, acc.MeanDepth(pixel), rays.intrinsics().fx,
                                    p.expected_subpixel_rms_px, plane, ground,
                                    PanelPixelParamsOf(p));
}

WindowFit FitPanelWindow(const metrics::RayTable& rays, const DepthAccumulator& acc,
                         const metrics::Plane& plane, const Eigen::Vector3d& up_hint,
                         const metrics::Plane* ground, const Eigen::Vector3d& seed_m,
                         const PanelParams& p) {
  WindowFit fit;
  metrics::PanelRectangle area;
  area.plane = plane;
  if (!metrics::PanelAxes(plane, up_hint, &area.axis_width, &area.axis_up)) {
    fit.message = "horizontal or degenerate plane";
    return fit;
  }
  area.center_m = seed_m - plane.Distance(seed_m) * plane.normal;
  if (!(area.center_m.z() > 0)) {
    fit.message = "plane behind the camera";
    return fit;
  }
  const double w = p.panel_width_m, h = p.panel_height_m;
  const double half_s = w * (0.5 + p.search_extent), half_t = h * (0.5 + p.search_extent);
  area.width_m = 2 * half_s;
  area.height_m = 2 * half_t;

  // Cells of a quarter of a pixel's footprint, at most kMaxCells per side.
  const camera::Intrinsics& in = rays.intrinsics();
  const Eigen::Vector2d foot = metrics::PixelFootprint(in, area);
  constexpr int kMaxCells = 1000;
  constexpr int kCellsPerPixel = 4;
  double cell_m = std::min(foot.x(), foot.y()) / kCellsPerPixel;
  cell_m = std::max({cell_m, 2 * half_s / kMaxCells, 2 * half_t / kMaxCells, 1e-4});
  const int ns = static_cast<int>(std::ceil(2 * half_s / cell_m));
  const int nt = static_cast<int>(std::ceil(2 * half_t / cell_m));

  // Image bounding box of the searched area (the whole image when a corner is behind).
  int u0 = 0, v0 = 0, u1 = in.width - 1, v1 = in.height - 1;
  {
    double umin = 1e18, umax = -1e18, vmin = 1e18, vmax = -1e18;
    bool all_front = true;
    for (const Eigen::Vector3d& corner : area.Corners()) {
      if (!(corner.z() > 1e-3)) {
        all_front = false;
        break;
      }
      const Eigen::Vector2d px = camera::Project(in, corner);
      umin = std::min(umin, px.x());
      umax = std::max(umax, px.x());
      vmin = std::min(vmin, px.y());
      vmax = std::max(vmax, px.y());
    }
    if (all_front) {
      u0 = std::max(0, static_cast<int>(std::floor(umin)) - 1);
      v0 = std::max(0, static_cast<int>(std::floor(vmin)) - 1);
      u1 = std::min(in.width - 1, static_cast<int>(std::ceil(umax)) + 1);
      v1 = std::min(in.height - 1, static_cast<int>(std::ceil(vmax)) + 1);
    }
  }

  // grid: the observed pixels, by class. area: the same with the holes enclosed by observed
  // pixels (within kFillPx on both sides along a row or a column) taking the class of the nearest
  // one, so that each surface counts by the area it covers, not by how many samples its texture
  // gave: a dense person beside a hole-ridden panel does not outweigh it.
  EvidenceGrid grid(ns, nt), area_grid(ns, nt);
  std::vector<Observed> observed;
  const int bw = u1 - u0 + 1, bh = v1 - v0 + 1;
  std::vector<int> cell_of(static_cast<std::size_t>(bw) * bh, -1);
  std::vector<std::uint8_t> label(cell_of.size(), 0);  // 0: none, else class + 1
  Eigen::Vector2d st;
  for (int v = v0; v <= v1; ++v) {
    for (int u = u0; u <= u1; ++u) {
      const std::uint32_t i = static_cast<std::uint32_t>(v) * in.width + u;
      if (!area.PlaneCoordinates(rays.Ray(i), &st)) continue;
      const int ci = static_cast<int>(std::floor((st.x() + half_s) / cell_m));
      const int cj = static_cast<int>(std::floor((st.y() + half_t) / cell_m));
      if (ci < 0 || cj < 0 || ci >= ns || cj >= nt) continue;
      const std::size_t b = static_cast<std::size_t>(v - v0) * bw + (u - u0);
      cell_of[b] = cj * ns + ci;
      if (acc.Count(i) == 0) continue;
      const PixelClass cls = ClassifyPixel(rays, acc, i, plane, ground, p);
      grid.Add(ci, cj, cls);
      observed.push_back({i, ci, cj, cls});
      label[b] = static_cast<std::uint8_t>(cls) + 1;
    }
  }
  grid.Integrate();
  {
    constexpr int kFillPx = 8;
    const std::vector<std::uint8_t> filled = FillEnclosedHoles(
        label, bw, bh, kFillPx, p.hole_fill == "sweeps" ? HoleFill::kSweeps : HoleFill::kOpenCv);
    for (std::size_t b = 0; b < filled.size(); ++b)
      if (cell_of[b] >= 0 && filled[b])
        area_grid.Add(cell_of[b] % ns, cell_of[b] / ns, static_cast<PixelClass>(filled[b] - 1));
  }
  area_grid.Integrate();

  // The window of the panel's size with the best evidence.
  // The ring starts one pixel footprint beyond the window: pixels straddling the edge are not
  // counted in it.
  const int ws = std::max(1, static_cast<int>(std::lround(w / cell_m)));
  const int wt = std::max(1, static_cast<int>(std::lround(h / cell_m)));
  const int kGuard = kCellsPerPixel;
  // Windows whose ring lies inside the searched area.
  const int ring = kGuard + std::max(1, static_cast<int>(std::lround(
                                          p.ring_width_frac * std::max(w, h) / cell_m)));
  if (ws + 2 * ring > ns || wt + 2 * ring > nt) {
    fit.message = "searched area smaller than the panel";
    return fit;
  }
  // The band one pixel wide just outside the window's sides and top must not run through the
  // plane: the panel's edges lie where its plane ends (background, holes, a gap), not through a
  // person beside it, however densely observed. Below, a post or stand may carry on.
  // Two scores of a window: by the area each class covers (where the panel is), then by the
  // observed pixels themselves (exactly where its edges run, to a fraction of a pixel).
  auto score_with = [&](const EvidenceGrid& g, int i, int j) {
    // The band lies one pixel out: a column straddling the panel's very edge is not held
    // against it.
    const long on_band = grid.Box(i - 2 * kGuard, j, i + ws + 2 * kGuard, j + wt + 2 * kGuard,
                                  EvidenceGrid::kOn) -
                         grid.Box(i - kGuard, j, i + ws + kGuard, j + wt + kGuard,
                                  EvidenceGrid::kOn);
    return g.Box(i, j, i + ws, j + wt, EvidenceGrid::kOn) -
           p.see_through_weight * g.Box(i, j, i + ws, j + wt, EvidenceGrid::kNegative) -
           p.front_weight * g.Box(i, j, i + ws, j + wt, EvidenceGrid::kFront) -
           p.edge_weight * on_band;
  };
  auto best_in = [&](const EvidenceGrid& g, int i0, int i1, int j0, int j1, int* bi, int* bj) {
    i0 = std::max(i0, ring);
    j0 = std::max(j0, ring);
    i1 = std::min(i1, ns - ws - ring);
    j1 = std::min(j1, nt - wt - ring);
    double best = -std::numeric_limits<double>::infinity();
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        const double score = score_with(g, i, j);
        if (score > best) {
          best = score;
          *bi = i;
          *bj = j;
        }
      }
    }
    // Where nothing observed bounds the panel (holes around it), windows tie over a range of
    // positions: take the middle of the run of ties through the best one, along each axis.
    int lo = *bi, hi = *bi;
    while (lo - 1 >= i0 && score_with(g, lo - 1, *bj) >= best) --lo;
    while (hi + 1 <= i1 && score_with(g, hi + 1, *bj) >= best) ++hi;
    *bi = (lo + hi) / 2;
    lo = hi = *bj;
    while (lo - 1 >= j0 && score_with(g, *bi, lo - 1) >= best) --lo;
    while (hi + 1 <= j1 && score_with(g, *bi, hi + 1) >= best) ++hi;
    *bj = (lo + hi) / 2;
  };
  int bi = ring, bj = ring;
  best_in(area_grid, ring, ns, ring, nt, &bi, &bj);
  const int local = 4 * kCellsPerPixel;  // refined within four pixels
  best_in(grid, bi - local, bi + local, bj - local, bj + local, &bi, &bj);
  WindowEvidence& ev = fit.evidence;
  ev.on_plane = static_cast<int>(grid.Box(bi, bj, bi + ws, bj + wt, EvidenceGrid::kOn));
  if (ev.on_plane < 3) {
    fit.message = "no observed pixel of the plane in any panel-sized window";
    return fit;
  }
  const double s0 = -half_s + bi * cell_m, s1 = s0 + ws * cell_m;
  const double t0 = -half_t + bj * cell_m, t1 = t0 + wt * cell_m;
  ev.ring_on_plane =
      static_cast<int>(grid.Box(bi - ring, bj - ring, bi + ws + ring, bj + wt + ring,
                                EvidenceGrid::kOn) -
                       grid.Box(bi - kGuard, bj - kGuard, bi + ws + kGuard, bj + wt + kGuard,
                                EvidenceGrid::kOn));

  metrics::PanelRectangle& rect = fit.rect;
  rect = area;
  rect.center_m = area.center_m + 0.5 * (s0 + s1) * area.axis_width + 0.5 * (t0 + t1) * area.axis_up;
  rect.width_m = w;
  rect.height_m = h;

  double cs_lo = 1e18, cs_hi = -1e18, ct_lo = 1e18, ct_hi = -1e18;
  int ring_all = 0;
  int side_on[4] = {0, 0, 0, 0}, side_all[4] = {0, 0, 0, 0};  // left, right, below, above
  for (const Observed& o : observed) {
    const bool in_s = o.cell_i >= bi && o.cell_i < bi + ws;
    const bool in_t = o.cell_j >= bj && o.cell_j < bj + wt;
    const double s = -half_s + (o.cell_i + 0.5) * cell_m;
    const double t = -half_t + (o.cell_j + 0.5) * cell_m;
    if (in_s && in_t) {
      switch (o.cls) {
        case PixelClass::kOnPlane:
          fit.on_plane_pixels.push_back(o.pixel);
          cs_lo = std::min(cs_lo, s);
          cs_hi = std::max(cs_hi, s);
          ct_lo = std::min(ct_lo, t);
          ct_hi = std::max(ct_hi, t);
          break;
        case PixelClass::kBehind: ++ev.behind; break;
        case PixelClass::kGround: ++ev.ground; break;
        case PixelClass::kInFront: ++ev.in_front; break;
        case PixelClass::kHole: break;
      }
      continue;
    }
    const bool in_ring = o.cell_i >= bi - ring && o.cell_i < bi + ws + ring &&
                         o.cell_j >= bj - ring && o.cell_j < bj + wt + ring;
    const bool in_guard = o.cell_i >= bi - kGuard && o.cell_i < bi + ws + kGuard &&
                          o.cell_j >= bj - kGuard && o.cell_j < bj + wt + kGuard;
    ring_all += in_ring && !in_guard;
    if (in_ring && !in_guard) {
      const bool side[4] = {o.cell_i < bi - kGuard, o.cell_i >= bi + ws + kGuard,
                            o.cell_j < bj - kGuard, o.cell_j >= bj + wt + kGuard};
      for (int k = 0; k < 4; ++k) {
        side_all[k] += side[k];
        side_on[k] += side[k] && o.cls == PixelClass::kOnPlane;
      }
    }
    if (o.cls != PixelClass::kOnPlane) continue;
    ++ev.cut_off_px;
    if (s < s0) ev.cut_off_left_m = std::max(ev.cut_off_left_m, s0 - s);
    if (s > s1) ev.cut_off_right_m = std::max(ev.cut_off_right_m, s - s1);
    if (t < t0) ev.cut_off_below_m = std::max(ev.cut_off_below_m, t0 - t);
    if (t > t1) ev.cut_off_above_m = std::max(ev.cut_off_above_m, t - t1);
  }
  ev.ring_observed = ring_all;
  constexpr int kMinSidePixels = 5;
  for (int k = 0; k < 4; ++k)
    ev.occupied_sides += side_all[k] >= kMinSidePixels && 2 * side_on[k] > side_all[k];
  ev.covered_width_m = cs_hi - cs_lo + cell_m;
  ev.covered_height_m = ct_hi - ct_lo + cell_m;
  std::sort(fit.on_plane_pixels.begin(), fit.on_plane_pixels.end());
  fit.success = true;
  return fit;
}

WindowFit FitAndRefinePanel(const metrics::RayTable& rays, const DepthAccumulator& acc,
                            metrics::Plane plane, const Eigen::Vector3d& up_hint,
                            const metrics::Plane* ground, const Eigen::Vector3d& seed_m,
                            const PanelParams& p, double* plane_rms_m) {
  WindowFit fit = FitPanelWindow(rays, acc, plane, up_hint, ground, seed_m, p);
  for (int it = 0; it < p.refine_iterations && fit.success; ++it) {
    // Plane in inverse depth over the window's on-plane pixels, 1/Z = k·(x/z, y/z, 1), each
    // pixel's mean weighted by its samples: least squares for noise along the rays.
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    for (std::uint32_t i : fit.on_plane_pixels) {
      const Eigen::Vector3d a = rays.Ray(i);
      const double n = acc.Count(i);
      ata += n * a * a.transpose();
      atb += n / acc.MeanDepth(i) * a;
    }
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(ata);
    const Eigen::Vector3d k = ldlt.solve(atb);
    const double len = k.norm();
    if (fit.on_plane_pixels.size() < 3 || ldlt.info() != Eigen::Success ||
        !(ldlt.rcond() > 1e-12) || !std::isfinite(len) || !(len > 0))
      break;
    metrics::Plane refined;
    refined.normal = -k / len;
    refined.offset_m = 1.0 / len;
    WindowFit next = FitPanelWindow(rays, acc, refined, up_hint, ground, fit.rect.center_m, p);
    if (!next.success) break;
    plane = refined;
    fit = std::move(next);
  }
  if (plane_rms_m && fit.success) {
    metrics::PlaneMoments m;
    for (std::uint32_t i : fit.on_plane_pixels) m.Add(acc.MeanDepth(i) * rays.Ray(i), acc.Count(i));
    const metrics::PlaneFit f = metrics::FitPlane(m);
    *plane_rms_m = f.ok ? f.rms_m : 0.0;
  }
  return fit;
}

metrics::PanelPixelParams PanelPixelParamsOf(const PanelParams& p) {
  metrics::PanelPixelParams q;
  q.baseline_m = p.baseline_m;
  q.expected_subpixel_rms_px = p.expected_subpixel_rms_px;
  q.sigma_k = p.evidence_sigma_k;
  q.plane_distance_m = p.plane_distance_m;
  q.ground_distance_m = p.ground_distance_m;
  q.refit_iterations = p.refine_iterations;
  q.pooled_frames = p.detection_frames;
  return q;
}

metrics::PanelPixels DecideRegionPixels(const DepthAccumulator& acc,
                                        const camera::Intrinsics& intrinsics,
                                        const metrics::PanelRegion& region,
                                        const metrics::Plane* ground, const PanelParams& p) {
  std::vector<metrics::PooledPixel> pooled(region.pixels.size());
  for (std::size_t k = 0; k < pooled.size(); ++k)
    pooled[k] = {acc.Count(region.pixels[k]), acc.SumCounts(region.pixels[k])};
  return metrics::DecidePanelPixels(intrinsics, region, pooled, acc.depth_units_m(), ground,
                                    PanelPixelParamsOf(p));
}

}  // namespace depthbias::panel
