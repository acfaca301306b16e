#pragma once
// Where a gap lies: the share of the squared scaled gap Σz² carried by a common offset, by each
// factor of the design (distance, angle, preset, light, emitter) and by each pair of them, from
// sequential least squares on indicator columns (the classical analysis of variance: exact
// shares for a balanced design such as the article's; for an unbalanced one, in the order
// listed), what is left being higher-order interactions and replicate noise; which metric
// carries it; and which cells depart significantly.

#include <string>
#include <vector>

#include "gap/design.h"

namespace depthbias::gap {

struct CellGap {
  int cell = 0;
  double chi2 = 0;      // Σ_k z² over the cell's metrics
  int df = 0;           // metrics it has
  double p_value = 1;   // of χ²_df
  int worst = 0;        // compared-metric index of the largest |z|
  double worst_z = 0;
};

struct Localization {
  std::vector<std::string> terms;               // "offset", "distance", ..., "rest"
  std::vector<double> overall_pct;              // share of Σz² over every metric, per term
  std::vector<std::vector<double>> metric_pct;  // [k][term] share of metric k's Σz²
  std::vector<double> metric_share_pct;         // [k] share of Σz² carried by metric k
  std::vector<double> metric_sum_sq;            // [k] Σz²
  std::vector<CellGap> significant;             // significant cells, largest χ² first
};

// z: [cell·K + k] scaled gaps (NaN: missing). A cell is significant when its χ² has a p-value
// below alpha / cells (Bonferroni over the table).
Localization Localize(const Design& design, const std::vector<double>& z, double alpha);
std::vector<CellGap> SignificantCells(const Design& design, const std::vector<double>& z,
                                      double alpha);

// P(χ²_df > x).
double ChiSquareSurvival(double x, int df);

}  // namespace depthbias::gap
