#pragma once
// The temporal disparity noise σ_d of a stereo camera, from consecutive frames of a static
// surface: between two frames the disparity d = f·B/Z seen by one pixel changes by the noise of
// both, so σ_d = σ(Δd)/√2. The spread is the RMS of Δd within five robust scales
// (1.4826·median |Δd|), which leaves out the few pixels where an edge or a hole changed the
// surface; the median alone would jump between the values of the camera's 1/32 px disparity
// lattice. A camera that moves between frames widens Δd: σ_d then comes out larger.
//
// The one estimator of σ_d: the metrics kernel measures it on the panel (the metrics CSV's
// sigma_d_px, lib/metrics), the obstacle detector at its obstacles (lib/detect/noise.h).

#include <cmath>
#include <cstddef>
#include <vector>

namespace depthbias::camera {

// |Δd| samples in a histogram (0.001 px bins up to 4 px, beyond: the top bin), so that any
// number of frames takes the same memory.
class TemporalNoise {
 public:
  TemporalNoise();
  // Δd = f·B·(1/Z − 1/Z_prev) of one pixel valid in two consecutive frames [px]; NaN ignored.
  // Inline: the metrics kernel calls it for every pixel of every frame.
  void Add(double delta_disparity_px) {
    AddEach(1, [delta_disparity_px](std::size_t) { return delta_disparity_px; });
  }
  // Add(delta(j)) for j in [0, n), the count kept in a register (a frame's pixels in one call:
  // one Add a pixel stores the count at every pixel, as the bins could alias it).
  template <typename F>
  void AddEach(std::size_t n, F delta) {
    long long* const bins = bins_.data();
    long long added = 0;
    for (std::size_t j = 0; j < n; ++j) {
      const double v = delta(j);
      if (std::isnan(v)) continue;
      const double a = std::fabs(v) / kBinPx;
      ++bins[a >= kBins - 1 ? kBins - 1 : static_cast<int>(a)];
      ++added;
    }
    pairs_ += added;
  }
  long long pairs() const { return pairs_; }
  // σ_d = RMS(Δd within 5·1.4826·median|Δd|)/√2 [px]; NaN without pairs.
  double SigmaPx() const;
  void Clear();

 private:
  static constexpr double kBinPx = 0.001;
  static constexpr int kBins = 4000;  // up to 4 px
  std::vector<long long> bins_;
  long long pairs_ = 0;
};

}  // namespace depthbias::camera
