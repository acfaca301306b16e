// The metrics-only path: DESIGN.md's panel metrics of one recording, from the sensor model
// evaluated on the panel's image footprint alone.

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "sim/parallel.h"
#include "sim/stereo_sim.h"

namespace depthbias::sim {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

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

double Median(std::vector<double> v) {
  if (v.empty()) return records::PanelMetrics::kMissing;
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  double m = v[mid];
  if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + mid));
  return m;
}

}  // namespace

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
  const PixelList region = sim.RegionPixels(mp.region_margin_px);
  result.region_px = static_cast<int>(region.size());
  m.region_px = static_cast<double>(region.size());
  if (region.empty()) {
    m.status = "no_panel";
    m.message = "the panel's image region is empty";
    return result;
  }

  // Normalized rays of the region's pixels.
  std::vector<double> xn(region.size()), yn(region.size());
  for (size_t i = 0; i < region.size(); ++i) {
    xn[i] = (window.u0 + region.window[i] % window.width - in.ppx) / in.fx;
    yn[i] = (window.v0 + region.window[i] / window.width - in.ppy) / in.fy;
  }

  // Per pixel over time: the count of valid samples, the sums of e = Z − Z_true and e², and of
  // a = f·B/Z − f·B/Z_true and a² (centred sums keep the variances exact in double); pooled: a
  // histogram of the depth counts for the median.
  const double fb = s.focal_px() * s.baseline_m;  // d = f·B/Z
  const size_t np = region.size();
  std::vector<double> z_true(np), d_true(np);
  for (size_t i = 0; i < np; ++i) {
    z_true[i] = sim.TrueDepth(region.window[i]);
    d_true[i] = fb / z_true[i];
  }
  std::vector<int> n_t(np, 0);
  std::vector<double> se(np, 0.0), se2(np, 0.0), sa(np, 0.0), sa2(np, 0.0);
  std::vector<std::uint64_t> histogram(65536, 0);  // of every valid sample's depth counts
  std::vector<std::uint16_t> counts;
  int frames_with_depth = 0;
  size_t n = 0;
  double sum_z = 0;
  for (int k = 0; k < frames; ++k) {
    sim.RenderPixels(k, region, &counts);
    bool any = false;
    for (size_t i = 0; i < np; ++i) {
      const std::uint16_t c = counts[i];
      if (!c) continue;
      any = true;
      ++histogram[c];
      const double z = c * s.depth_units_m;
      const double e = z - z_true[i];
      const double a = fb / z - d_true[i];
      ++n_t[i];
      se[i] += e;
      se2[i] += e * e;
      sa[i] += a;
      sa2[i] += a * a;
      sum_z += z;
    }
    frames_with_depth += any;
  }
  for (int c : n_t) n += c;
  m.frames = frames_with_depth;
  const double total = static_cast<double>(np) * frames;
  m.valid_pct = 100.0 * static_cast<double>(n) / total;
  m.hole_rate_pct = 100.0 - m.valid_pct;
  if (n == 0) {
    m.status = "no_panel";
    m.message = "no valid depth in the panel's region";
    return result;
  }
  m.mean_m = sum_z / n;
  {
    // Median of the pooled depths (the mean of the two middle ones for an even count): the
    // samples of ranks n/2 and (n − 1)/2 (from 0), read off the histogram.
    auto at_rank = [&](size_t rank) {
      size_t below = 0;
      for (size_t c = 0;; ++c) {
        below += histogram[c];
        if (below > rank) return c * s.depth_units_m;
      }
    };
    m.median_m = 0.5 * (at_rank((n - 1) / 2) + at_rank(n / 2));
  }

  // The plane fitted to the points (least squares: the eigenvector of the smallest eigenvalue of
  // their covariance; RMS orthogonal distance = √λ_min). A pixel's points lie on its ray r:
  // p = Z·r, so Σp = r·ΣZ and Σp·pᵀ = r·rᵀ·ΣZ², taken relative to the true panel centre o.
  const Eigen::Vector3d origin = result.truth.panel.center_m;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < np; ++i) {
    if (!n_t[i]) continue;
    const Eigen::Vector3d ray(xn[i], yn[i], 1.0);
    const double sz = n_t[i] * z_true[i] + se[i];  // ΣZ
    const double sz2 = n_t[i] * z_true[i] * z_true[i] + 2 * z_true[i] * se[i] + se2[i];  // ΣZ²
    sum += sz * ray - n_t[i] * origin;
    outer += sz2 * ray * ray.transpose() - sz * (ray * origin.transpose() +
                                                 origin * ray.transpose()) +
             n_t[i] * origin * origin.transpose();
  }
  const Eigen::Vector3d mean_p = sum / n;
  const Eigen::Matrix3d cov = outer / n - mean_p * mean_p.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d normal = eig.eigenvectors().col(0);
  if (normal.z() > 0) normal = -normal;
  m.plane_std_m = std::sqrt(std::max(eig.eigenvalues()(0), 0.0));

  // Direction and range of the panel's centre: the centroid's ray at the median depth.
  const Eigen::Vector3d centroid = mean_p + origin;
  const double cx = centroid.x() / centroid.z(), cy = centroid.y() / centroid.z();
  m.range_m = m.median_m * std::sqrt(1 + cx * cx + cy * cy);
  m.azimuth_deg = std::atan(cx) * kRadToDeg;
  m.elevation_deg = std::atan2(-cy, std::sqrt(1 + cx * cx)) * kRadToDeg;

  // The plane in disparity, D = f·B/Z = α·x/z + β·y/z + γ, by ordinary least squares (noise is
  // in disparity, along the rays; no tilt bias when the depth noise outgrows the panel): its
  // normal (α, β, γ) gives the tilt, its residuals the Depth Quality Tool's subpixel RMS. With
  // g = (x/z, y/z, 1) per pixel and a = D − D_true: residual = a − c, c = g·θ − D_true.
  Eigen::Matrix3d gram = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < np; ++i) {
    if (!n_t[i]) continue;
    const Eigen::Vector3d g(xn[i], yn[i], 1.0);
    gram += n_t[i] * g * g.transpose();
    rhs += g * (sa[i] + n_t[i] * d_true[i]);
  }
  const Eigen::Vector3d theta = gram.ldlt().solve(rhs);
  m.normal_tilt_deg = std::acos(std::min(1.0, std::fabs(theta.z()) / theta.norm())) * kRadToDeg;
  Eigen::Vector3d along_w = normal.cross(Eigen::Vector3d::UnitY());
  if (along_w.norm() < 1e-9) along_w = Eigen::Vector3d::UnitX();
  along_w.normalize();
  const Eigen::Vector3d along_h = normal.cross(along_w).normalized();
  double sum_sq_d = 0, w_lo = 1e18, w_hi = -1e18, h_lo = 1e18, h_hi = -1e18;
  for (size_t i = 0; i < np; ++i) {
    if (!n_t[i]) continue;
    const Eigen::Vector3d ray(xn[i], yn[i], 1.0);
    const double c = ray.dot(theta) - d_true[i];
    sum_sq_d += sa2[i] - 2 * c * sa[i] + n_t[i] * c * c;
    const Eigen::Vector3d p = (z_true[i] + se[i] / n_t[i]) * ray - centroid;
    w_lo = std::min(w_lo, p.dot(along_w));
    w_hi = std::max(w_hi, p.dot(along_w));
    h_lo = std::min(h_lo, p.dot(along_h));
    h_hi = std::max(h_hi, p.dot(along_h));
  }
  m.subpixel_rms_px = std::sqrt(std::max(sum_sq_d, 0.0) / n);
  m.panel_width_m = w_hi - w_lo;
  m.panel_height_m = h_hi - h_lo;

  std::vector<double> temporal;  // per-pixel sample standard deviation over time
  for (size_t i = 0; i < np; ++i)
    if (n_t[i] >= 2)
      temporal.push_back(
          std::sqrt(std::max(se2[i] - se[i] * se[i] / n_t[i], 0.0) / (n_t[i] - 1)));
  m.temporal_std_m = Median(temporal);
  if (!result.truth.scenario_listed)
    m.message = "scenario " + cell.light + "/" + cell.preset + " not in the sensor table: "
                "fallback noise and invalidation used";
  return result;
}

std::vector<CellMetricsResult> SimulateCellsMetrics(const SimParams& params,
                                                    const std::vector<Cell>& cells,
                                                    const MetricsParams& metrics) {
  std::vector<CellMetricsResult> out(cells.size());
  detail::ForEachIndex(cells.size(), metrics.threads,
                       [&](size_t i) { out[i] = SimulateMetrics(params, cells[i], metrics); });
  return out;
}

std::vector<CellMetricsResult> SimulateProtocolMetrics(const SimParams& params,
                                                       const MetricsParams& metrics) {
  return SimulateCellsMetrics(params, MakeCells(params.protocol), metrics);
}

}  // namespace depthbias::sim
