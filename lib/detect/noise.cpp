#include "detect/noise.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace depthbias::detect {
namespace {

constexpr double kBinPx = 0.001;
constexpr int kBins = 4000;  // up to 4 px

}  // namespace

bool NoiseParams::IsValid(std::string* why) const {
  if (frames < 2 || frames > 100000) {
    if (why) *why = "noise.frames must be in [2, 100000] (pairs of consecutive frames)";
    return false;
  }
  if (min_pairs < 1) {
    if (why) *why = "noise.min_pairs must be >= 1";
    return false;
  }
  return true;
}

TemporalNoise::TemporalNoise() : bins_(kBins, 0) {}

void TemporalNoise::Add(double delta_disparity_px) {
  if (std::isnan(delta_disparity_px)) return;
  const double a = std::fabs(delta_disparity_px) / kBinPx;
  const int bin = a >= kBins - 1 ? kBins - 1 : static_cast<int>(a);
  ++bins_[static_cast<size_t>(bin)];
  ++pairs_;
}

double TemporalNoise::SigmaPx() const {
  if (pairs_ == 0) return std::numeric_limits<double>::quiet_NaN();
  // The median |Δd|: the bin holding the middle sample, interpolated within it.
  const double half = 0.5 * static_cast<double>(pairs_);
  long long below = 0;
  for (int b = 0; b < kBins; ++b) {
    const long long n = bins_[static_cast<size_t>(b)];
    if (static_cast<double>(below + n) >= half && n > 0) {
      const double within = (half - static_cast<double>(below)) / static_cast<double>(n);
      const double median_px = (b + std::clamp(within, 0.0, 1.0)) * kBinPx;
      return 1.4826 * median_px / std::sqrt(2.0);
    }
    below += n;
  }
  return (kBins - 1) * kBinPx * 1.4826 / std::sqrt(2.0);
}

void TemporalNoise::Clear() {
  std::fill(bins_.begin(), bins_.end(), 0);
  pairs_ = 0;
}

}  // namespace depthbias::detect
