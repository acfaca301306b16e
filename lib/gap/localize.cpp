#include "gap/localize.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

namespace depthbias::gap {
namespace {

// Indicator columns (levels 1 … L − 1) of a factor, over the given cells.
Eigen::MatrixXd Indicators(const std::vector<int>& level, const std::vector<int>& cells) {
  int levels = 0;
  for (int c : cells) levels = std::max(levels, level[c] + 1);
  Eigen::MatrixXd m =
      Eigen::MatrixXd::Zero(static_cast<int>(cells.size()), std::max(0, levels - 1));
  for (size_t i = 0; i < cells.size(); ++i)
    if (level[cells[i]] > 0) m(static_cast<int>(i), level[cells[i]] - 1) = 1;
  return m;
}

double Rss(const Eigen::MatrixXd& x, const Eigen::VectorXd& y) {
  if (x.cols() == 0) return y.squaredNorm();
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(x);
  const Eigen::VectorXd beta = qr.solve(y);
  return (y - x * beta).squaredNorm();
}

// Regularized lower incomplete gamma P(a, x) (series, then continued fraction).
double GammaP(double a, double x) {
  if (x <= 0) return 0;
  const double lg = std::lgamma(a);
  if (x < a + 1) {
    double sum = 1 / a, term = sum;
    for (int n = 1; n < 1000; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::fabs(term) < std::fabs(sum) * 1e-15) break;
    }
    return sum * std::exp(-x + a * std::log(x) - lg);
  }
  double b = x + 1 - a, c = 1e300, dd = 1 / b, h = dd;
  for (int i = 1; i < 1000; ++i) {
    const double an = -i * (i - a);
    b += 2;
    dd = an * dd + b;
    if (std::fabs(dd) < 1e-300) dd = 1e-300;
    c = b + an / c;
    if (std::fabs(c) < 1e-300) c = 1e-300;
    dd = 1 / dd;
    const double del = dd * c;
    h *= del;
    if (std::fabs(del - 1) < 1e-15) break;
  }
  return 1 - std::exp(-x + a * std::log(x) - lg) * h;
}

}  // namespace

double ChiSquareSurvival(double x, int df) {
  if (df <= 0) return 1;
  return std::clamp(1 - GammaP(0.5 * df, 0.5 * x), 0.0, 1.0);
}

std::vector<CellGap> SignificantCells(const Design& d, const std::vector<double>& z, double alpha) {
  const int k_count = d.num_metrics();
  std::vector<CellGap> out;
  for (int c = 0; c < d.num_cells(); ++c) {
    CellGap g;
    g.cell = c;
    for (int k = 0; k < k_count; ++k) {
      const double v = z[static_cast<size_t>(c) * k_count + k];
      if (!std::isfinite(v)) continue;
      g.chi2 += v * v;
      ++g.df;
      if (std::fabs(v) > std::fabs(g.worst_z)) g.worst_z = v, g.worst = k;
    }
    g.p_value = ChiSquareSurvival(g.chi2, g.df);
    if (g.df > 0 && g.p_value < alpha / d.num_cells()) out.push_back(g);
  }
  std::sort(out.begin(), out.end(),
            [](const CellGap& a, const CellGap& b) { return a.chi2 > b.chi2; });
  return out;
}

Localization Localize(const Design& d, const std::vector<double>& z, double alpha) {
  Localization loc;
  constexpr int kFactors = 5;
  const char* names[kFactors] = {"distance", "angle", "preset", "light", "emitter"};
  const Factor factors[kFactors] = {Factor::kDistance, Factor::kAngle, Factor::kPreset,
                                    Factor::kLight, Factor::kEmitter};
  std::vector<std::vector<int>> level;
  for (int f = 0; f < kFactors; ++f) level.push_back(FactorLevels(d, factors[f]));
  loc.terms.push_back("offset");
  for (int f = 0; f < kFactors; ++f) loc.terms.push_back(names[f]);
  std::vector<std::pair<int, int>> pairs;
  for (int a = 0; a < kFactors; ++a)
    for (int b = a + 1; b < kFactors; ++b) {
      pairs.emplace_back(a, b);
      loc.terms.push_back(std::string(names[a]) + "×" + names[b]);
    }
  loc.terms.push_back("rest");
  const int k_count = d.num_metrics();
  const int n_terms = static_cast<int>(loc.terms.size());
  std::vector<double> total_ss(n_terms, 0.0);
  double total = 0;
  for (int k = 0; k < k_count; ++k) {
    std::vector<int> cells;
    for (int c = 0; c < d.num_cells(); ++c)
      if (std::isfinite(z[static_cast<size_t>(c) * k_count + k])) cells.push_back(c);
    Eigen::VectorXd y(static_cast<int>(cells.size()));
    for (size_t i = 0; i < cells.size(); ++i)
      y(static_cast<int>(i)) = z[static_cast<size_t>(cells[i]) * k_count + k];
    std::vector<Eigen::MatrixXd> blocks;
    blocks.push_back(Eigen::MatrixXd::Ones(static_cast<int>(cells.size()), 1));
    std::vector<Eigen::MatrixXd> main;
    for (int f = 0; f < kFactors; ++f) {
      main.push_back(Indicators(level[f], cells));
      blocks.push_back(main.back());
    }
    for (const auto& [a, b] : pairs) {
      Eigen::MatrixXd m(static_cast<int>(cells.size()), main[a].cols() * main[b].cols());
      for (int i = 0; i < main[a].cols(); ++i)
        for (int j = 0; j < main[b].cols(); ++j)
          m.col(i * main[b].cols() + j) = main[a].col(i).cwiseProduct(main[b].col(j));
      blocks.push_back(m);
    }
    std::vector<double> ss(n_terms, 0.0);
    const double sum_sq = y.squaredNorm();
    double prev = sum_sq;
    Eigen::MatrixXd x(static_cast<int>(cells.size()), 0);
    for (size_t t = 0; t < blocks.size(); ++t) {
      Eigen::MatrixXd grown(x.rows(), x.cols() + blocks[t].cols());
      grown << x, blocks[t];
      x = grown;
      const double rss = cells.empty() ? 0.0 : Rss(x, y);
      ss[t] = std::max(0.0, prev - rss);
      prev = rss;
    }
    ss[n_terms - 1] = prev;
    std::vector<double> pct(n_terms, 0.0);
    for (int t = 0; t < n_terms; ++t) {
      pct[t] = sum_sq > 0 ? 100 * ss[t] / sum_sq : 0.0;
      total_ss[t] += ss[t];
    }
    total += sum_sq;
    loc.metric_pct.push_back(pct);
    loc.metric_sum_sq.push_back(sum_sq);
  }
  for (int t = 0; t < n_terms; ++t)
    loc.overall_pct.push_back(total > 0 ? 100 * total_ss[t] / total : 0.0);
  for (double s : loc.metric_sum_sq)
    loc.metric_share_pct.push_back(total > 0 ? 100 * s / total : 0);
  loc.significant = SignificantCells(d, z, alpha);
  return loc;
}

}  // namespace depthbias::gap
