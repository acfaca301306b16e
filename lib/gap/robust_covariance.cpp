#include "gap/robust_covariance.h"

#include <limits>
#include <map>

namespace depthbias::gap {

Eigen::MatrixXd ClusterRobustCovariance(const Eigen::MatrixXd& inv, const Eigen::MatrixXd& j,
                                        const std::vector<double>& r,
                                        const std::vector<long long>& unit) {
  const Eigen::Index p = inv.rows();
  std::map<long long, Eigen::VectorXd> score;
  for (size_t i = 0; i < unit.size() && i < r.size(); ++i) {
    auto it = score.find(unit[i]);
    if (it == score.end()) it = score.emplace(unit[i], Eigen::VectorXd::Zero(p)).first;
    it->second += j.row(static_cast<Eigen::Index>(i)).transpose() * r[i];
  }
  const double g = static_cast<double>(score.size());
  if (score.size() < 2)
    return Eigen::MatrixXd::Constant(p, p, std::numeric_limits<double>::quiet_NaN());
  Eigen::MatrixXd meat = Eigen::MatrixXd::Zero(p, p);
  for (const auto& [u, s] : score) meat += s * s.transpose();
  return g / (g - 1) * inv * meat * inv;
}

}  // namespace depthbias::gap
