// The placement law's accessors and the spreads' coupling to the median (placement.h).
#include <algorithm>
#include <cmath>

#include "gap/placement.h"

namespace depthbias::gap {

double PlacementEstimate::Law(int k, int metric, double distance_m) const {
  if (a.empty()) return 0;
  if (metric == kMedianBias) return a[k] + b[k] * distance_m;
  const double own = a[k] * PlacementShape(metric, distance_m);
  return std::max(own, Floor(k, distance_m));
}

double PlacementEstimate::Sensitivity(int k, double distance_m) const {
  const int m = floor_of.empty() ? -1 : floor_of[k];
  if (m < 0 || floor_distance_m.empty()) return 0.0;
  size_t i = 0;
  for (size_t j = 1; j < floor_distance_m.size(); ++j)
    if (std::fabs(floor_distance_m[j] - distance_m) < std::fabs(floor_distance_m[i] - distance_m))
      i = j;
  return sensitivity[k][i];
}

double PlacementEstimate::Floor(int k, double distance_m) const {
  const double s = Sensitivity(k, distance_m);
  return s == 0 ? 0.0 : std::fabs(s) * Law(floor_of[k], kMedianBias, distance_m);
}

double PlacementEstimate::Shared(int k, int metric, int t) const {
  if (tau.empty() || !(tau[k][t] > 0)) return 0.0;
  const double dist = point_distance_m[t];
  if (metric == kMedianBias) return std::min(1.0, Law(k, metric, dist) / tau[k][t]);
  const double c = coupling.empty() ? 0.0 : coupling[k];
  return std::copysign(c * std::min(1.0, Floor(k, dist) / tau[k][t]), Sensitivity(k, dist));
}

void EstimateCoupling(PlacementEstimate* pe) {
  const int kk = static_cast<int>(pe->floor_of.size());
  const int np = pe->num_points;
  pe->coupling.assign(kk, 0.0);
  for (int k = 0; k < kk; ++k) {
    const int m = pe->floor_of[k];
    if (m < 0) continue;
    double sxy = 0, sxx = 0;
    for (int t = 0; t < np; ++t) {
      const double x = pe->Sensitivity(k, pe->point_distance_m[t]) * pe->departure[m][t];
      const double y = pe->departure[k][t];
      if (pe->flagged[m][t] || pe->flagged[k][t] || !std::isfinite(x) || !std::isfinite(y))
        continue;
      sxy += x * y, sxx += x * x;
    }
    pe->coupling[k] = sxx > 0 ? std::clamp(sxy / sxx, 0.0, 1.0) : 0.0;
  }
}

}  // namespace depthbias::gap
