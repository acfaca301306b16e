#pragma once
// The disparity noise σ_d of a recording, from its own frames: the temporal spread at its
// obstacles. Between two consecutive frames the disparity d = f·B/Z of a static surface seen by
// one pixel changes by the noise of both frames, so σ_d = σ(Δd)/√2. The spread is the RMS of
// Δd within five robust scales (1.4826·median |Δd|), which leaves out the few pixels where an
// edge or a hole changed the surface; the median alone would jump between the values of the
// camera's 1/32 px disparity lattice. A camera that moves between frames widens Δd: σ_d then
// comes out larger, which makes the margin wider, not narrower.

#include <string>
#include <vector>

namespace depthbias::detect {

struct NoiseParams {
  bool from_frames = true;  // false: σ_d of the margin is cluster.disparity_noise_px
  int frames = 30;          // the first frames of a recording the estimate is taken from
  int min_pairs = 200;      // fewer pixel pairs at obstacles: the estimate is not used [pairs]
  bool IsValid(std::string* why) const;
};

// |Δd| samples in a histogram (0.001 px bins up to 4 px, beyond: the top bin), so that any
// number of frames takes the same memory.
class TemporalNoise {
 public:
  TemporalNoise();
  void Add(double delta_disparity_px);
  long long pairs() const { return pairs_; }
  // σ_d = RMS(Δd within 5·1.4826·median|Δd|)/√2 [px]; NaN without pairs.
  double SigmaPx() const;
  void Clear();

 private:
  std::vector<long long> bins_;
  long long pairs_ = 0;
};

}  // namespace depthbias::detect
