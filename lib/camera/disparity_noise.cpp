#include "camera/disparity_noise.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace depthbias::camera {

TemporalNoise::TemporalNoise() : bins_(kBins, 0) {}

double TemporalNoise::SigmaPx() const {
  if (pairs_ == 0) return std::numeric_limits<double>::quiet_NaN();
  // A robust scale first: 1.4826·median|Δd|, the bin holding the middle sample. The camera's
  // disparities lie on a lattice (1/32 px on the D455), so this median jumps from one lattice
  // value to the next; it only sets where outliers begin.
  const double half = 0.5 * static_cast<double>(pairs_);
  long long below = 0;
  int median_bin = kBins - 1;
  for (int b = 0; b < kBins; ++b) {
    below += bins_[static_cast<size_t>(b)];
    if (static_cast<double>(below) >= half) {
      median_bin = b;
      break;
    }
  }
  const double scale_px = 1.4826 * (median_bin + 1) * kBinPx;
  // Then the RMS of |Δd| within 5 robust scales (a normal loses 0.001 % of its variance there;
  // an edge or a hole that changed the surface lies beyond): σ_d = RMS(Δd)/√2.
  const double cut_px = 5.0 * scale_px;
  double sum2 = 0.0;
  long long n = 0;
  for (int b = 0; b < kBins - 1; ++b) {
    const double centre_px = (b + 0.5) * kBinPx;
    if (centre_px > cut_px) break;
    const long long c = bins_[static_cast<size_t>(b)];
    sum2 += static_cast<double>(c) * centre_px * centre_px;
    n += c;
  }
  if (n == 0) return std::numeric_limits<double>::quiet_NaN();
  return std::sqrt(sum2 / static_cast<double>(n) / 2.0);
}

void TemporalNoise::Clear() {
  std::fill(bins_.begin(), bins_.end(), 0);
  pairs_ = 0;
}

}  // namespace depthbias::camera
