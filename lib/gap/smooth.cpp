#include "gap/smooth.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include <Eigen/Dense>

#include "gap/noise.h"

namespace depthbias::gap {
namespace {

// Calls f(origin, stride, axis) for every line of a surface's grid along a continuous axis.
void ForEachLine(const Surface& surf,
                 const std::function<void(int origin, int stride, const Axis& axis)>& f) {
  const Candidate& cand = surf.candidate;
  for (size_t a = 0; a < cand.axes.size(); ++a) {
    const Axis& axis = cand.axes[a];
    if (axis.discrete) continue;
    const int n_a = static_cast<int>(axis.nodes.size());
    const int n_other = surf.num_nodes / n_a;
    const bool slow = cand.axes.size() > 1 && a == 0;  // axis 0 of two: stride of axis 1's size
    for (int other = 0; other < n_other; ++other)
      f(slow ? other : other * n_a, slow ? n_other : 1, axis);
  }
}

}  // namespace

std::vector<double> NodeScatter(const Design& d, const Surface& surf, const Simulations& s) {
  const int kk = d.num_metrics();
  std::vector<double> out(kk, 0.0);
  for (int k = 0; k < kk; ++k) {
    const int m = d.metrics[k];
    if (!InfoOf(m).window) continue;
    std::vector<double> e;
    ForEachLine(surf, [&](int origin, int stride, const Axis& axis) {
      const int n = static_cast<int>(axis.nodes.size());
      for (int c = 0; c < d.num_cells(); ++c) {
        const double* row = &surf.table[(static_cast<size_t>(c) * kk + k) * surf.num_nodes];
        const double shape = NoiseShape(m, s.depth_m[c]);
        for (int j = 1; j + 1 < n; ++j) {
          const double x0 = Coordinate(axis, axis.nodes[j - 1]),
                       x1 = Coordinate(axis, axis.nodes[j]),
                       x2 = Coordinate(axis, axis.nodes[j + 1]);
          const double w0 = (x2 - x1) / (x2 - x0), w2 = 1 - w0;
          const double r = (row[origin + j * stride] - w0 * row[origin + (j - 1) * stride] -
                            w2 * row[origin + (j + 1) * stride]) /
                           std::sqrt(1 + w0 * w0 + w2 * w2) / shape;
          if (std::isfinite(r)) e.push_back(r);
        }
      }
    });
    if (e.size() >= 8) out[k] = 1.4826 * MedianAbs(e);
  }
  return out;
}

// The smoothers of one line of nodes (x, the pinned node) over the strengths tried: they do not
// depend on the values, so one set serves every row of a surface.
class LineSmoother {
 public:
  LineSmoother(const double* x, int n, int pinned) : n_(n), pinned_(pinned) {
    if (n < 4) return;
    for (int j = 0; j < n; ++j)
      if (!std::isfinite(x[j])) return;
    // Second divided differences: (D f)_j ≈ f'' at node j + 1.
    Eigen::MatrixXd dm = Eigen::MatrixXd::Zero(n - 2, n);
    for (int j = 1; j + 1 < n; ++j) {
      const double h0 = x[j] - x[j - 1], h1 = x[j + 1] - x[j];
      if (!(h0 > 0 && h1 > 0)) return;
      dm(j - 1, j - 1) = 2 / (h0 * (h0 + h1));
      dm(j - 1, j) = -2 / (h0 * h1);
      dm(j - 1, j + 1) = 2 / (h1 * (h0 + h1));
    }
    const Eigen::MatrixXd p = dm.transpose() * dm;
    Eigen::VectorXd w = Eigen::VectorXd::Ones(n);
    if (pinned >= 0 && pinned < n) w[pinned] = 1e9;  // held at its value
    const Eigen::MatrixXd wd = w.asDiagonal();
    // A log grid of strengths from interpolation to a straight line, relative to the
    // penalty's scale.
    const double unit = static_cast<double>(n) / std::max(p.trace(), 1e-300);
    for (int i = -8; i <= 16; ++i) {
      const double lambda = unit * std::pow(10.0, 0.5 * i);
      smoothers_.push_back(Eigen::MatrixXd(wd + lambda * p).ldlt().solve(wd));
    }
  }

  // The smooth whose unbiased risk estimate Σ_free (y − ŷ)² + 2σ²·tr(S) is least (the nodes
  // themselves, tr S = n, if none is below theirs).
  void Apply(double* y, double sigma) const {
    if (smoothers_.empty() || !(sigma > 0)) return;
    for (int j = 0; j < n_; ++j)
      if (!std::isfinite(y[j])) return;
    const Eigen::Map<Eigen::VectorXd> yv(y, n_);
    const double s2 = sigma * sigma;
    double best_risk = 2 * s2 * n_;
    Eigen::VectorXd best;
    for (const Eigen::MatrixXd& sm : smoothers_) {
      const Eigen::VectorXd f = sm * yv;
      double risk = 2 * s2 * sm.trace();
      for (int j = 0; j < n_; ++j)
        if (j != pinned_) risk += (yv[j] - f[j]) * (yv[j] - f[j]);
      if (risk < best_risk) best_risk = risk, best = f;
    }
    if (best.size() == 0) return;
    for (int j = 0; j < n_; ++j)
      if (j != pinned_) y[j] = best[j];
  }

 private:
  int n_ = 0, pinned_ = -1;
  std::vector<Eigen::MatrixXd> smoothers_;
};

void SmoothAlong(const double* x, double* y, int n, int pinned, double sigma) {
  LineSmoother(x, n, pinned).Apply(y, sigma);
}

void SmoothSurfaces(const Design& d, Simulations* s) {
  const int kk = d.num_metrics();
  for (Surface& surf : s->surfaces) {
    const std::vector<double> scatter = NodeScatter(d, surf, *s);
    const Candidate& cand = surf.candidate;
    ForEachLine(surf, [&](int origin, int stride, const Axis& axis) {
      const int n = static_cast<int>(axis.nodes.size());
      std::vector<double> x(n), y(n);
      for (int j = 0; j < n; ++j) x[j] = Coordinate(axis, axis.nodes[j]);
      // The node where the effect is absent, the line's other axis as it stands.
      int pinned = -1;
      for (int j = 0; j < n && pinned < 0; ++j) {
        std::vector<double> values(cand.axes.size());
        const int node = origin + j * stride;
        if (cand.axes.size() == 1) {
          values[0] = axis.nodes[j];
        } else {
          const int n1 = static_cast<int>(cand.axes[1].nodes.size());
          values[0] = cand.axes[0].nodes[node / n1];
          values[1] = cand.axes[1].nodes[node % n1];
        }
        if (IsNeutral(cand, values)) pinned = j;
      }
      const LineSmoother smoother(x.data(), n, pinned);
      for (int c = 0; c < d.num_cells(); ++c)
        for (int k = 0; k < kk; ++k) {
          if (!InfoOf(d.metrics[k]).window) continue;
          double* row = &surf.table[(static_cast<size_t>(c) * kk + k) * surf.num_nodes];
          for (int j = 0; j < n; ++j) y[j] = row[origin + j * stride];
          const double z = s->depth_m[c];
          const double spread = scatter[k] * NoiseShape(d.metrics[k], z);
          const double q = QuantizationRms(d.metrics[k], z, s->sensor.focal_px(),
                                           s->sensor.baseline_m, s->sensor.subpixel_step_px,
                                           s->base[static_cast<size_t>(c) * kk + k]);
          smoother.Apply(y.data(), std::sqrt(spread * spread + q * q));
          for (int j = 0; j < n; ++j) row[origin + j * stride] = y[j];
        }
    });
  }
}

Surface AverageOverPlacement(const Design& d, const Simulations& s, const Surface& surface,
                             const std::vector<double>& rel_of_cell) {
  Surface out = surface;
  const Candidate& cand = surface.candidate;
  const int kk = d.num_metrics();
  const auto kmed = std::find(d.metrics.begin(), d.metrics.end(), kMedianBias);
  if (!cand.range_law || kmed == d.metrics.end()) return out;
  const int km = static_cast<int>(kmed - d.metrics.begin());
  ForEachLine(surface, [&](int origin, int stride, const Axis& axis) {
    const int n = static_cast<int>(axis.nodes.size());
    int pinned = -1;
    for (int j = 0; j < n && pinned < 0; ++j)
      if (cand.axes.size() == 1 && IsNeutral(cand, {axis.nodes[j]})) pinned = j;
    if (pinned < 0) return;  // a line off the neutral value: nothing to keep it to
    std::vector<double> zm(n), w(static_cast<size_t>(n) * n);
    for (int c = 0; c < d.num_cells(); ++c) {
      const double rel = c < static_cast<int>(rel_of_cell.size()) ? rel_of_cell[c] : 0.0;
      if (!(rel > 0)) continue;
      const double* med = &surface.table[(static_cast<size_t>(c) * kk + km) * surface.num_nodes];
      bool finite = true;
      for (int j = 0; j < n; ++j) {
        zm[j] = s.depth_m[c] + med[origin + j * stride];
        finite = finite && std::isfinite(zm[j]) && zm[j] > 0;
      }
      if (!finite) continue;
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const double u = (zm[i] - zm[j]) / (rel * zm[j]);
          w[static_cast<size_t>(j) * n + i] = std::exp(-0.5 * u * u);
        }
      for (int k = 0; k < kk; ++k) {
        if (!InfoOf(d.metrics[k]).placement_average) continue;
        const double* in = &surface.table[(static_cast<size_t>(c) * kk + k) * surface.num_nodes];
        double* row = &out.table[(static_cast<size_t>(c) * kk + k) * surface.num_nodes];
        std::vector<double> avg(n);
        bool ok = true;
        for (int j = 0; j < n; ++j) {
          double sw = 0, sy = 0;
          for (int i = 0; i < n; ++i) {
            sw += w[static_cast<size_t>(j) * n + i];
            sy += w[static_cast<size_t>(j) * n + i] * in[origin + i * stride];
          }
          avg[j] = sy / sw;
          ok = ok && std::isfinite(avg[j]);
        }
        if (!ok) continue;
        const double keep = in[origin + pinned * stride] - avg[pinned];
        for (int j = 0; j < n; ++j) row[origin + j * stride] = avg[j] + keep;
      }
    }
  });
  return out;
}

}  // namespace depthbias::gap
