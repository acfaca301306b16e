// Private to gap.
#pragma once
// The covariance of a least-squares fit's coordinates when its rows are not independent within
// a unit. Every recording of a test point and every metric of it share the panel's placement:
// the whitening (fit.h (2)) takes out each metric's share of it, but a panel set 30 cm off moves
// the median, the spreads and the valid share of all its recordings together, and one
// displacement is then read as many independent ones. Liang and Zeger's sandwich counts each
// unit once: H⁻¹ (Σ_u s_u s_uᵀ) H⁻¹ · G / (G − 1), s_u = Σ over unit u's rows of J_rᵀ r_r, over
// the G units that hold rows.

#include <vector>

#include <Eigen/Dense>

namespace depthbias::gap {

// `inv`: H⁻¹ (JᵀJ, prior rows included); `j`, `r`: the whitened Jacobian and residuals, whose
// first unit.size() rows are the data's (the rest priors, left out of the sum); unit[i]: data
// row i's unit. NaN where fewer than two units hold rows.
Eigen::MatrixXd ClusterRobustCovariance(const Eigen::MatrixXd& inv, const Eigen::MatrixXd& j,
                                        const std::vector<double>& r,
                                        const std::vector<long long>& unit);

}  // namespace depthbias::gap
