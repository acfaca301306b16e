#include "sim/stereo_sim.h"

#include "common/hash.h"
#include "common/parallel.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <system_error>
#include <thread>
#include <type_traits>

namespace depthbias::sim {
namespace {

constexpr int kGaussBits = 12;  // bits of a draw that pick the normal quantile
constexpr int kValidBits = 12;  // bits of the hole draw: p resolved to 1/4096
constexpr int kMixBits = 8;     // bits of the edge-mixing fraction
constexpr std::uint64_t kGolden = 0x9E3779B97F4A7C15ULL;

using common::Mix64;  // a counter-based generator: h(seed + i·γ) for draw i

// Runs f(v_begin, v_end) over [0, rows) split into `threads` bands of rows.
template <typename F>
void ForRows(int rows, int threads, F f) {
  common::ForEachBand(static_cast<std::size_t>(std::max(rows, 0)), std::clamp(threads, 1, 16),
                      [&](std::size_t a, std::size_t b) {
                        f(static_cast<int>(a), static_cast<int>(b));
                      });
}

// The 32 bits of a pair hash that belong to draw `counter` (its low half for even counters).
inline std::uint32_t HalfOf(std::uint64_t pair_hash, std::uint64_t counter) {
  return static_cast<std::uint32_t>(counter & 1 ? pair_hash >> 32 : pair_hash);
}

// 2^12 standard normal quantiles at the midpoints (i + ½)/2^12, rescaled to unit variance:
// a 12-bit index draws N(0, 1) truncated at ±3.5σ.
const std::array<float, 1 << kGaussBits>& GaussTable() {
  static const std::array<float, 1 << kGaussBits> table = [] {
    std::array<float, 1 << kGaussBits> t{};
    const int n = 1 << kGaussBits;
    std::vector<double> q(n);
    double sum_sq = 0;
    for (int i = 0; i < n; ++i) {
      const double p = (i + 0.5) / n;
      double lo = -10, hi = 10;  // Φ(x) = erfc(−x/√2)/2, inverted by bisection
      for (int it = 0; it < 80; ++it) {
        const double mid = 0.5 * (lo + hi);
        (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p ? lo : hi) = mid;
      }
      q[i] = 0.5 * (lo + hi);
      sum_sq += q[i] * q[i];
    }
    const double scale = 1.0 / std::sqrt(sum_sq / n);
    for (int i = 0; i < n; ++i) t[i] = static_cast<float>(q[i] * scale);
    return t;
  }();
  return table;
}

double Logit(double p) {
  p = std::clamp(p, 1e-12, 1.0 - 1e-12);
  return std::log(p / (1 - p));
}

// Chebyshev dilation of a 0/1 mask by r (separable max filter).
std::vector<unsigned char> Dilate(const std::vector<unsigned char>& in, int w, int h, int r) {
  if (r <= 0) return in;
  std::vector<unsigned char> rows(in.size(), 0), out(in.size(), 0);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      unsigned char m = 0;
      for (int du = std::max(0, u - r); du <= std::min(w - 1, u + r) && !m; ++du)
        m = in[static_cast<size_t>(v) * w + du];
      rows[static_cast<size_t>(v) * w + u] = m;
    }
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      unsigned char m = 0;
      for (int dv = std::max(0, v - r); dv <= std::min(h - 1, v + r) && !m; ++dv)
        m = rows[static_cast<size_t>(dv) * w + u];
      out[static_cast<size_t>(v) * w + u] = m;
    }
  return out;
}

// Separable min or max filter of radius r. Each output starts from its own input and takes its
// neighbours in ascending order (as a loop over them would); the loops over the neighbours'
// offsets run outside those over the pixels, so that the pixels' are vectorized.
template <bool kMax>
std::vector<float> Extreme(const std::vector<float>& in, int w, int h, int r) {
  auto better = [](float a, float b) { return kMax ? std::max(a, b) : std::min(a, b); };
  std::vector<float> rows(in);
  for (int v = 0; v < h; ++v) {
    const float* const src = in.data() + static_cast<size_t>(v) * w;
    float* const dst = rows.data() + static_cast<size_t>(v) * w;
    for (int du = -r; du <= r; ++du) {
      const int u_begin = std::max(0, -du), u_end = std::min(w, w - du);
      for (int u = u_begin; u < u_end; ++u) dst[u] = better(dst[u], src[u + du]);
    }
  }
  std::vector<float> out(rows);
  for (int v = 0; v < h; ++v) {
    float* const dst = out.data() + static_cast<size_t>(v) * w;
    for (int dv = std::max(0, v - r); dv <= std::min(h - 1, v + r); ++dv) {
      const float* const src = rows.data() + static_cast<size_t>(dv) * w;
      for (int u = 0; u < w; ++u) dst[u] = better(dst[u], src[u]);
    }
  }
  return out;
}

// Bit for bit, like scene.h's Identical.
bool Same(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

bool Identical(const camera::Intrinsics& a, const camera::Intrinsics& b) {
  if (!(a.width == b.width && a.height == b.height && Same(a.fx, b.fx) && Same(a.fy, b.fy) &&
        Same(a.ppx, b.ppx) && Same(a.ppy, b.ppy) && a.model == b.model))
    return false;
  for (size_t i = 0; i < a.coeffs.size(); ++i)
    if (!Same(a.coeffs[i], b.coeffs[i])) return false;
  return true;
}

bool Identical(const Window& a, const Window& b) {
  return a.u0 == b.u0 && a.v0 == b.v0 && a.width == b.width && a.height == b.height;
}

// Everything the depth-count table reads.
struct CountsKey {
  double fb, step, min_depth_m, max_depth_m, depth_scale, depth_units_m;
  double phase;  // the lattice's shift, in steps (dither_quantization)
};
bool Identical(const CountsKey& a, const CountsKey& b) {
  return Same(a.fb, b.fb) && Same(a.step, b.step) && Same(a.min_depth_m, b.min_depth_m) &&
         Same(a.max_depth_m, b.max_depth_m) && Same(a.depth_scale, b.depth_scale) &&
         Same(a.depth_units_m, b.depth_units_m) && Same(a.phase, b.phase);
}

// Everything a window's ray cast and its depth edges read: the scene (its background moved by
// region_spill), the panel as placed (the protocol, the cell and the departures that move it),
// the camera, the window, f·B and the edge parameters.
struct CastKey {
  SceneParams scene;
  PanelPose panel;
  camera::Intrinsics intrinsics;
  Window window;
  double fb = 0;
  int edge_band_px = 0;
  double edge_jump_rel = 0;
};
bool Identical(const CastKey& a, const CastKey& b) {  // the cheap fields first
  return Identical(a.window, b.window) && Same(a.fb, b.fb) && Identical(a.panel, b.panel) &&
         a.edge_band_px == b.edge_band_px && Same(a.edge_jump_rel, b.edge_jump_rel) &&
         Identical(a.intrinsics, b.intrinsics) && Identical(a.scene, b.scene);
}

bool Same(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return Same(a.x(), b.x()) && Same(a.y(), b.y()) && Same(a.z(), b.z());
}
bool Identical(const metrics::PanelRectangle& a, const metrics::PanelRectangle& b) {
  return Same(a.center_m, b.center_m) && Same(a.width_m, b.width_m) &&
         Same(a.height_m, b.height_m) && Same(a.plane.offset_m, b.plane.offset_m) &&
         Same(a.plane.normal, b.plane.normal) && Same(a.axis_width, b.axis_width) &&
         Same(a.axis_up, b.axis_up);
}

// Everything RegionPixels reads: the rectangle the region is drawn on, the camera, the window,
// the margin and the region spill.
struct RegionKey {
  metrics::PanelRectangle rect;
  camera::Intrinsics intrinsics;
  Window window;
  double margin_px = 0;
  double spill_px = 0;
};
bool Identical(const RegionKey& a, const RegionKey& b) {
  return Identical(a.window, b.window) && Same(a.margin_px, b.margin_px) &&
         Same(a.spill_px, b.spill_px) && Identical(a.rect, b.rect) &&
         Identical(a.intrinsics, b.intrinsics);
}
struct RegionData {
  std::vector<int> window;      // PixelList::window; PixelList::image is region.pixels
  metrics::PanelRegion region;  // limited to the window
};

// Immutable values shared between simulations and threads, under keys compared whole and bit
// for bit. At most `budget` bytes are held, none over a quarter of it;
// when full, the least recently used values go first (the recordings of one simulation of a
// table share a value only if it outlives the recordings between them: a budget below one
// table's worth drops every value before it is used again). A value dropped here lives on in
// the simulations that hold it.
template <typename Key, typename Value>
class SharedCache {
 public:
  explicit SharedCache(std::size_t budget) : budget_(budget) {}

  std::shared_ptr<const Value> Find(const Key& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (Entry& e : entries_)
      if (Identical(e.key, key)) {
        e.last_use = ++clock_;
        return e.value;
      }
    return nullptr;
  }

  // False if the value is not kept (too large, or another thread was first).
  bool Insert(const Key& key, std::shared_ptr<const Value> value, std::size_t bytes) {
    if (bytes > budget_ / 4) return false;
    std::lock_guard<std::mutex> lock(mutex_);
    for (const Entry& e : entries_)
      if (Identical(e.key, key)) return false;
    while (held_ + bytes > budget_ && !entries_.empty()) {
      const auto victim =
          std::min_element(entries_.begin(), entries_.end(), [](const Entry& a, const Entry& b) {
            return a.last_use < b.last_use;
          });
      held_ -= victim->bytes;
      *victim = std::move(entries_.back());
      entries_.pop_back();
    }
    entries_.push_back({key, std::move(value), bytes, ++clock_});
    held_ += bytes;
    return true;
  }

 private:
  struct Entry {
    Key key;
    std::shared_ptr<const Value> value;
    std::size_t bytes;
    std::uint64_t last_use;
  };
  std::mutex mutex_;
  std::vector<Entry> entries_;
  std::size_t budget_;
  std::size_t held_ = 0;
  std::uint64_t clock_ = 0;
};

// The article's 128 cells stand at 16 placements: their windows' casts take 3.0 MB, their regions
// 1.3 MB, and one sensor's count table 10 kB (17 with the dithered lattices').
constexpr std::size_t kCountsCacheBytes = std::size_t{512} << 10;
// Lattice phases of dither_quantization.
constexpr int kDitherPhases = 16;
double DitherPhase(int j) { return (j + 0.5) / kDitherPhases - 0.5; }
constexpr std::size_t kCastCacheBytes = std::size_t{4} << 20;
constexpr std::size_t kRegionCacheBytes = std::size_t{2} << 20;

}  // namespace

// The depth counts of quantized disparity k·step, [0] = 0: no depth.
struct StereoSim::CountsTable {
  int k_min = 0;
  int k_max = 0;
  std::vector<std::uint16_t> counts;
};

// A window's ray cast (row-major window pixels) and its depth edges.
struct StereoSim::CastMaps {
  std::vector<float> true_depth_m;     // 0 where nothing is hit
  std::vector<unsigned char> surface;  // Surface
  std::vector<float> texture;
  std::vector<float> disparity;        // f·B/Z, 0 where nothing is hit
  std::vector<unsigned char> near_edge;  // on the far side of a depth edge, within its band

  void Cast(const SceneParams& scene, const PanelPose& panel, const camera::Intrinsics& in,
            const Window& window, double fb, int edge_band_px, double edge_jump_rel,
            int threads);
  std::size_t bytes() const {
    return sizeof(*this) + true_depth_m.size() * (3 * sizeof(float) + 2);
  }
};

bool SimParams::IsValid(std::string* why) const {
  if (!protocol.IsValid(why)) return false;
  if (!sensor.IsValid(why)) return false;
  if (!(departures.sigma_gain >= 0) || !(departures.invalid_odds_gain >= 0) ||
      !(departures.depth_scale > 0) || !(departures.region_spill_px >= 0) ||
      !(departures.background_depth_rel >= 0)) {
    if (why) *why = "effects: gains, spill and background must be >= 0 and the depth scale > 0";
    return false;
  }
  return true;
}


std::uint64_t CellSeed(std::uint64_t seed, const std::string& cell_name) {
  std::uint64_t h = 0xCBF29CE484222325ULL;  // FNV-1a of the name
  for (unsigned char c : cell_name) h = (h ^ c) * 0x100000001B3ULL;
  return Mix64(Mix64(seed + kGolden) ^ h);
}

StereoSim::StereoSim(const SimParams& params, const Cell& cell, int threads)
    : StereoSim(params, cell,
                Window{0, 0, params.sensor.intrinsics.width, params.sensor.intrinsics.height},
                threads) {}

StereoSim::StereoSim(const SimParams& params, const Cell& cell, const Window& window,
                     int threads)
    : params_(params), cell_(cell), window_(window), threads_(threads) {
  std::string why;
  if (!params_.IsValid(&why)) throw std::invalid_argument("simulation parameters: " + why);
  const auto& in = params_.sensor.intrinsics;
  if (window_.width < 0 || window_.height < 0 || window_.u0 < 0 || window_.v0 < 0 ||
      window_.u0 + window_.width > in.width || window_.v0 + window_.height > in.height)
    throw std::invalid_argument("simulation window outside the image");
  Build();
}

void StereoSim::Build() {
  const SensorParams& s = params_.sensor;
  const Departures& dep = params_.departures;
  const auto& in = s.intrinsics;
  const double fb = s.focal_px() * s.baseline_m;  // d = f·B/Z

  truth_.panel = PlacePanel(params_.protocol.scene, params_.protocol.distance_is, cell_,
                            dep.range_vs_depth_weight, dep.panel_yaw_deg);
  truth_.panel_depth_m = truth_.panel.center_m.z();
  truth_.panel_range_m = truth_.panel.center_m.norm();
  truth_.panel_angle_deg =
      std::acos(truth_.panel_depth_m / truth_.panel_range_m) * 180.0 / M_PI;
  truth_.scenario = s.Scenario(cell_.light, cell_.preset, &truth_.scenario_listed);
  truth_.cell_seed = CellSeed(params_.seed, cell_.name);
  sigma_px_ = truth_.scenario.sigma_d_px * dep.sigma_gain;
  sigma_f_ = static_cast<float>(sigma_px_);
  gauss_ = GaussTable().data();

  // Quantized disparity k·step → depth counts; out of [min, max] depth → no entry. The same
  // table for every recording of a sensor.
  inv_step_ = 1.0 / s.subpixel_step_px;
  static SharedCache<CountsKey, CountsTable> counts_cache(kCountsCacheBytes);
  // The lattice shifted by `phase` steps: index k stands for disparity (k − phase)·step.
  auto counts_table = [&](double phase) {
    const CountsKey key{fb, s.subpixel_step_px, s.min_depth_m, s.max_depth_m,
                        dep.depth_scale, s.depth_units_m, phase};
    std::shared_ptr<const CountsTable> found = counts_cache.Find(key);
    if (found) return found;
    auto t = std::make_shared<CountsTable>();
    t->k_min = static_cast<int>(std::ceil(fb / (s.max_depth_m * s.subpixel_step_px)));
    t->k_max = static_cast<int>(std::floor(fb / (s.min_depth_m * s.subpixel_step_px)));
    t->k_min = std::max(t->k_min, 1);
    t->counts.assign(static_cast<size_t>(t->k_max) + 1, 0);  // [0] stays 0: no depth
    for (int k = t->k_min; k <= t->k_max; ++k) {
      const double depth_m = dep.depth_scale * fb / ((k - phase) * s.subpixel_step_px);  // f·B/d
      t->counts[k] =
          static_cast<std::uint16_t>(std::min(65535.0, std::round(depth_m / s.depth_units_m)));
    }
    counts_cache.Insert(key, t, sizeof(CountsTable) + t->counts.size() * 2);
    return std::shared_ptr<const CountsTable>(std::move(t));
  };
  counts_table_ = counts_table(0.0);
  dither_tables_.clear();
  dither_counts_.clear();
  dither_offset_.assign(kDitherPhases, 0.f);
  if (params_.dither_quantization)
    for (int j = 0; j < kDitherPhases; ++j) {
      dither_tables_.push_back(counts_table(DitherPhase(j)));
      dither_counts_.push_back(dither_tables_.back()->counts.data());
      dither_offset_[j] = static_cast<float>(DitherPhase(j) * s.subpixel_step_px);
    }
  k_min_ = counts_table_->k_min;
  k_max_ = counts_table_->k_max;
  counts_of_k_ = counts_table_->counts.data();
  inv_step_f_ = static_cast<float>(inv_step_);
  k_min_f_ = static_cast<float>(k_min_);
  k_end_f_ = static_cast<float>(k_max_ + 1);

  // True depth by ray casting (region_spill may bring the background nearer), and the depth
  // edges: once per geometry, shared by the simulations that leave it alone.
  const int w = window_.width, h = window_.height;
  const size_t n = static_cast<size_t>(w) * h;
  CastKey cast_key{params_.protocol.scene, truth_.panel, in, window_, fb, s.edge_band_px,
                   s.edge_jump_rel};
  if (dep.background_depth_rel > 0)
    cast_key.scene.background_distance_m = dep.background_depth_rel * truth_.panel_depth_m;
  static SharedCache<CastKey, CastMaps> cast_cache(kCastCacheBytes);
  cast_ = cast_cache.Find(cast_key);
  std::shared_ptr<CastMaps> unshared;  // a cast this simulation alone holds
  if (!cast_) {
    auto c = std::make_shared<CastMaps>();
    c->Cast(cast_key.scene, truth_.panel, in, window_, fb, s.edge_band_px, s.edge_jump_rel,
            threads_);
    if (!cast_cache.Insert(cast_key, c, c->bytes())) unshared = c;
    cast_ = std::move(c);
  }
  true_depth_m_ = cast_->true_depth_m.data();
  surface_ = cast_->surface.data();
  const float* const disparity = cast_->disparity.data();
  const float* const texture = cast_->texture.data();
  const unsigned char* const near_edge = cast_->near_edge.data();

  // Edge mixing: the other side of the nearest edge within the mixing width.
  const int mix_w = static_cast<int>(dep.edge_mix_width_px);
  mixing_ = mix_w > 0 && dep.edge_mix_strength > 0;
  mix_delta_px_.clear();
  if (mixing_) {
    mix_delta_px_.assign(n, 0.f);
    const std::vector<float> lo = Extreme<false>(cast_->disparity, w, h, mix_w);
    const std::vector<float> hi = Extreme<true>(cast_->disparity, w, h, mix_w);
    for (size_t i = 0; i < n; ++i) {
      if (!surface_[i] || !(hi[i] > lo[i] * (1 + s.edge_jump_rel))) continue;
      const float d = disparity[i];
      const float other = (d - lo[i] > hi[i] - d) ? lo[i] : hi[i];
      mix_delta_px_[i] = static_cast<float>(dep.edge_mix_strength * (other - d));
    }
  }

  // Static disparity and hole probability. Without static departures the static disparity is
  // the cast's (d + 0.0 rounds back to d).
  const bool own_disparity = !dep.static_disparity.empty();
  std::shared_ptr<std::vector<float>> own;
  if (own_disparity) own = std::make_shared<std::vector<float>>(n, 0.f);
  float* const own_d = own_disparity ? own->data() : nullptr;
  const float* const static_d = own_disparity ? own_d : disparity;
  valid_threshold_.assign(n, 0);
  const double logit_scenario = Logit(truth_.scenario.invalid_prob);
  const bool offset_varies = !dep.disparity_over_time.empty();
  const double g = dep.invalid_odds_gain;
  ForRows(h, threads_, [&](int v_begin, int v_end) {
    double last_texture = -1, last_p = 0;
    double last_hole_p = NAN;  // the hole probability last_threshold is of (NaN: none yet)
    std::uint16_t last_threshold = 0;
    for (int v = v_begin; v < v_end; ++v) {
      const double yn = (window_.v0 + v - in.ppy) / in.fy;
      for (int u = 0; u < w; ++u) {
        const size_t i = static_cast<size_t>(v) * w + u;
        if (!surface_[i]) continue;
        if (own_disparity) {
          const double xn = (window_.u0 + u - in.ppx) / in.fx;
          own_d[i] = static_cast<float>(disparity[i] + dep.StaticDisparityPx(xn, yn));
        }
        double t = texture[i];
        if (cell_.emitter_on) {
          const double reach = s.emitter_reach_m / true_depth_m_[i];
          t += dep.emitter_gain * s.emitter_texture * std::min(1.0, reach * reach);
        }
        if (t != last_texture) {  // surfaces share textures: the logistic once per change
          last_texture = t;
          last_p = 1.0 / (1.0 + std::exp(-(logit_scenario -
                                           s.texture_slope * (t - s.reference_texture))));
        }
        double p = last_p;
        if (truth_.scenario.invalid_prob <= 0) p = 0;
        if (truth_.scenario.invalid_prob >= 1) p = 1;
        if (near_edge[i]) p = std::max(p, s.edge_invalid_prob);
        if (!(p == last_hole_p)) {  // neighbours mostly share it: the odds once per change
          last_hole_p = p;
          p = g * p / (1 - p + g * p);  // odds × g
          if (!std::isfinite(p)) p = 1;
          last_threshold = static_cast<std::uint16_t>(  // rounded: the value is >= 0
              std::clamp(1.0 - p, 0.0, 1.0) * (1 << kValidBits) + 0.5);
        }
        valid_threshold_[i] = last_threshold;
        // A disparity that noise (truncated at 3.5σ) and mixing cannot bring into range never
        // gives depth: skip its draws (not with a time-varying offset, which has no bound).
        const double reach_px =
            3.6 * sigma_px_ + (mixing_ ? std::fabs(mix_delta_px_[i]) : 0.f);
        if (!offset_varies &&
            ((static_d[i] + reach_px) * inv_step_ + 0.5 < k_min_ ||
             (static_d[i] - reach_px) * inv_step_ + 0.5 >= k_max_ + 1))
          valid_threshold_[i] = 0;
      }
    }
  });
  if (own_disparity)
    static_disparity_px_ = std::move(own);
  else
    static_disparity_px_ = std::shared_ptr<const std::vector<float>>(cast_, &cast_->disparity);
  if (unshared) {  // what only the static maps read (a whole image's cast is not shared)
    unshared->texture = std::vector<float>();
    unshared->near_edge = std::vector<unsigned char>();
  }
}

void StereoSim::CastMaps::Cast(const SceneParams& scene, const PanelPose& panel,
                               const camera::Intrinsics& in, const Window& window, double fb,
                               int edge_band_px, double edge_jump_rel, int threads) {
  const int w = window.width, h = window.height;
  const size_t n = static_cast<size_t>(w) * h;
  RayCaster caster(scene, panel);
  true_depth_m.assign(n, 0.f);
  surface.assign(n, 0);
  texture.assign(n, 0.f);
  disparity.assign(n, 0.f);
  float* const true_depth_p = true_depth_m.data();
  unsigned char* const surface_p = surface.data();
  float* const texture_p = texture.data();
  float* const disparity_p = disparity.data();
  ForRows(h, threads, [&](int v_begin, int v_end) {
    for (int v = v_begin; v < v_end; ++v) {
      const double yn = (window.v0 + v - in.ppy) / in.fy;
      for (int u = 0; u < w; ++u) {
        const double xn = (window.u0 + u - in.ppx) / in.fx;
        const Hit hit = caster.Cast(xn, yn);
        const size_t i = static_cast<size_t>(v) * w + u;
        true_depth_p[i] = static_cast<float>(hit.depth_m);
        surface_p[i] = static_cast<unsigned char>(hit.surface);
        texture_p[i] = static_cast<float>(hit.texture);
        if (hit.surface != Surface::kNone) disparity_p[i] = static_cast<float>(fb / hit.depth_m);
      }
    }
  });

  // Depth edges, occlusion side: where two 4-neighbours' depths jump (relative jump beyond
  // edge_jump_rel), the far pixel is on the edge's far side, the background one camera sees and
  // the other does not. It carries the near side's depth; pixels within edge_band_px of it that
  // are markedly farther than that near depth are in the band.
  near_edge.assign(n, 0);
  if (edge_band_px > 0) {
    std::vector<float> near_z(n, 1e30f);
    auto mark = [&](size_t a, size_t b) {
      if (!surface_p[a] && !surface_p[b]) return;
      if (!surface_p[a] || !surface_p[b]) {  // nothing hit beyond the edge: no depth there anyway
        const size_t far = surface_p[a] ? b : a, near = surface_p[a] ? a : b;
        near_z[far] = std::min(near_z[far], true_depth_p[near]);
        return;
      }
      const float za = true_depth_p[a], zb = true_depth_p[b];
      if (std::fabs(za - zb) <= edge_jump_rel * std::min(za, zb)) return;
      const size_t far = za > zb ? a : b;
      near_z[far] = std::min(near_z[far], std::min(za, zb));
    };
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) {
        const size_t i = static_cast<size_t>(v) * w + u;
        if (u + 1 < w) mark(i, i + 1);
        if (v + 1 < h) mark(i, i + w);
      }
    // Each marked pixel stamps its band (edges are sparse: this is the minimum filter of near_z
    // evaluated where it is finite).
    const int r = edge_band_px - 1;
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) {
        const float z = near_z[static_cast<size_t>(v) * w + u];
        if (z >= 1e30f) continue;
        for (int bv = std::max(0, v - r); bv <= std::min(h - 1, v + r); ++bv)
          for (int bu = std::max(0, u - r); bu <= std::min(w - 1, u + r); ++bu) {
            const size_t i = static_cast<size_t>(bv) * w + bu;
            if (surface_p[i] && z * (1 + edge_jump_rel) < true_depth_p[i]) near_edge[i] = 1;
          }
      }
  }
}

std::uint64_t StereoSim::Counter(int frame_index, int pixel) const {
  const auto& in = params_.sensor.intrinsics;
  const int u = window_.u0 + pixel % window_.width;
  const int v = window_.v0 + pixel / window_.width;
  return static_cast<std::uint64_t>(frame_index) * static_cast<std::uint64_t>(in.width) *
             in.height +
         static_cast<std::uint64_t>(v) * in.width + u;
}

// One 64-bit hash serves two neighbouring draws (counters 2j and 2j + 1): 32 bits each, of
// which 12 pick the normal quantile, 12 the hole draw and 8 the mixing fraction.
inline std::uint64_t StereoSim::PairHash(std::uint64_t counter) const {
  return Mix64(truth_.cell_seed + (counter >> 1) * kGolden);
}

namespace {

// Raw views of the static maps for the inner loops (the compiler cannot prove that the frame
// being written does not alias the maps' vectors, so it would reload them at every pixel).
struct Maps {
  const float* disparity;
  const float* mix_delta;
  const std::uint16_t* valid_threshold;
  const float* gauss;
  const std::uint16_t* counts_of_k;
  float inv_step, k_min, k_end, offset, sigma;
  // dither_quantization: each image pixel's lattice phase (of kDitherPhases) picks its shift
  // (in disparity) and its table; null: the camera's one lattice.
  const std::uint16_t* const* dither_counts;
  const float* dither_offset;
};

// The lattice phase of an image pixel: fixed by its index alone, so that every frame and every
// run of a pixel reads on one lattice (its spread over time is the camera's), while the pixels
// of a region take every phase.
inline int PhaseOfPixel(std::uint64_t image_pixel) {
  return static_cast<int>((static_cast<std::uint32_t>(image_pixel) * 0x9E3779B1u) >> 28);
}

// kMasked: the count's index selected by a mask, not a branch (faster where holes are frequent
// and unpredictable, as on the panel; the branch is faster over whole frames, where the pixels
// that never give depth come in runs).
template <bool kMixing, bool kMasked = false>
inline std::uint16_t Draw(const Maps& m, std::uint32_t bits, int pixel,
                          std::uint64_t image_pixel) {
  const std::uint32_t uniform_valid = (bits >> kGaussBits) & ((1u << kValidBits) - 1);
  // d + offset + σ·n + mixing, quantized to the subpixel step: k = floor(d/step + ½). Single
  // precision: d < 200 px is resolved to 2e-5 px, far below the 1/32 px step.
  float d = m.disparity[pixel] + m.offset + m.sigma * m.gauss[bits & ((1u << kGaussBits) - 1)];
  if constexpr (kMixing) {
    const float mix = static_cast<float>(bits >> (kGaussBits + kValidBits)) *
                      (1.0f / (1 << kMixBits));
    d += mix * m.mix_delta[pixel];
  }
  const std::uint16_t* counts_of_k = m.counts_of_k;
  if (m.dither_counts) {
    const int j = PhaseOfPixel(image_pixel);
    d += m.dither_offset[j];
    counts_of_k = m.dither_counts[j];
  }
  const float x = d * m.inv_step + 0.5f;
  // Valid and within [min, max] depth; counts_of_k[0] = 0 stands for "no depth". (Branch-free
  // forms of this select measured slower here than the branch.)
  const bool ok = (uniform_valid < m.valid_threshold[pixel]) & (x >= m.k_min) & (x < m.k_end);
  if constexpr (kMasked) {
    // x clamped to [0, k_end] first (NaN to 0), so that its conversion is always defined; the
    // same index wherever ok.
    const int k = static_cast<int>(std::min(m.k_end, std::max(0.0f, x)));
    return counts_of_k[k & -static_cast<int>(ok)];
  } else {
    return counts_of_k[ok ? static_cast<int>(x) : 0];
  }
}

}  // namespace

void StereoSim::Render(int frame_index, records::DepthFrame* frame, int threads) const {
  const auto& in = params_.sensor.intrinsics;
  const auto& proto = params_.protocol;
  frame->width = in.width;
  frame->height = in.height;
  frame->depth_units_m = params_.sensor.depth_units_m;
  frame->frame_number = static_cast<std::uint64_t>(frame_index) + 1;
  frame->timestamp_ms = 1000.0 * frame_index / proto.fps;
  const size_t n = static_cast<size_t>(in.width) * in.height;
  const bool whole = window_.width == in.width && window_.height == in.height;
  if (frame->counts.size() != n || !whole) frame->counts.assign(n, 0);
  const float offset = static_cast<float>(
      params_.departures.DisparityAtTimePx(frame_index / params_.protocol.fps));
  const Maps maps{static_disparity_px_->data(), mix_delta_px_.data(), valid_threshold_.data(),
                  gauss_, counts_of_k_, inv_step_f_, k_min_f_, k_end_f_, offset, sigma_f_,
                  dither_counts_.empty() ? nullptr : dither_counts_.data(),
                  dither_offset_.data()};
  std::uint16_t* const counts = frame->counts.data();
  const std::uint64_t seed = truth_.cell_seed;
  // Pixels go by pairs of draws (counters 2j, 2j + 1) that share one hash. A pixel that never
  // gives depth has a valid threshold of 0 and draws counts_of_k[0] = 0.
  auto rows = [&, counts, seed](auto mixing, int v_begin, int v_end) {
    constexpr bool kMix = decltype(mixing)::value;
    const Maps m = maps;  // a local copy the compiler keeps in registers
    const int w = window_.width;
    auto one = [&](std::uint16_t* row, int base, std::uint64_t counter, int u, size_t image) {
      const std::uint64_t c = counter + static_cast<std::uint64_t>(u);
      row[u] = Draw<kMix>(m, HalfOf(Mix64(seed + (c >> 1) * kGolden), c), base + u, image + u);
    };
    for (int v = v_begin; v < v_end; ++v) {
      const size_t image = static_cast<size_t>(window_.v0 + v) * in.width + window_.u0;
      std::uint16_t* const row = counts + image;
      const int base = v * w;
      const std::uint64_t counter = Counter(frame_index, base);
      int u = 0;
      if (counter & 1 && w > 0) one(row, base, counter, u++, image);
      for (; u + 1 < w; u += 2) {
        const std::uint64_t hash = Mix64(seed + ((counter + u) >> 1) * kGolden);
        row[u] = Draw<kMix>(m, static_cast<std::uint32_t>(hash), base + u, image + u);
        row[u + 1] =
            Draw<kMix>(m, static_cast<std::uint32_t>(hash >> 32), base + u + 1, image + u + 1);
      }
      if (u < w) one(row, base, counter, u, image);
    }
  };
  if (mixing_)
    ForRows(window_.height, threads, [&](int a, int b) { rows(std::true_type{}, a, b); });
  else
    ForRows(window_.height, threads, [&](int a, int b) { rows(std::false_type{}, a, b); });
}

void StereoSim::RenderPixels(int frame_index, const PixelList& pixels,
                             std::vector<std::uint16_t>* counts) const {
  counts->resize(pixels.window.size());
  RenderPixels(frame_index, pixels, counts->data());
}

void StereoSim::RenderPixels(int frame_index, const PixelList& pixels,
                             std::uint16_t* const out) const {
  const float offset = static_cast<float>(
      params_.departures.DisparityAtTimePx(frame_index / params_.protocol.fps));
  const Maps maps{static_disparity_px_->data(), mix_delta_px_.data(), valid_threshold_.data(),
                  gauss_, counts_of_k_, inv_step_f_, k_min_f_, k_end_f_, offset, sigma_f_,
                  dither_counts_.empty() ? nullptr : dither_counts_.data(),
                  dither_offset_.data()};
  const auto& in = params_.sensor.intrinsics;
  const std::uint64_t frame_base = static_cast<std::uint64_t>(frame_index) *
                                   static_cast<std::uint64_t>(in.width) * in.height;
  const size_t n = pixels.window.size();
  const int* const window = pixels.window.data();
  const std::uint64_t* const image = pixels.image.data();
  const std::uint64_t seed = truth_.cell_seed;
  auto run = [&, out, window, image, seed](auto mixing) {
    constexpr bool kMix = decltype(mixing)::value;
    const Maps m = maps;  // a local copy the compiler keeps in registers
    std::uint64_t pair = ~0ULL, hash = 0;
    for (size_t i = 0; i < n; ++i) {
      const std::uint64_t c = frame_base + image[i];
      if ((c >> 1) != pair) {  // neighbours in a row share their hash
        pair = c >> 1;
        hash = Mix64(seed + pair * kGolden);
      }
      out[i] = Draw<kMix, true>(m, HalfOf(hash, c), window[i], image[i]);
    }
  };
  if (mixing_)
    run(std::true_type{});
  else
    run(std::false_type{});
}

metrics::PanelRectangle PanelRectangleOf(const PanelPose& pose) {
  metrics::PanelRectangle rect;
  rect.plane.normal = pose.normal.normalized();
  rect.plane.offset_m = -rect.plane.normal.dot(pose.center_m);
  rect.center_m = pose.center_m;
  rect.axis_width = pose.axis_width;
  rect.axis_up = -pose.axis_height;
  rect.width_m = pose.width_m;
  rect.height_m = pose.height_m;
  return rect;
}

PixelList StereoSim::RegionPixels(double margin_px, metrics::PanelRegion* region_out,
                                  const metrics::PanelRectangle* drawn) const {
  return RegionPixels(margin_px, region_out, drawn, params_.departures.region_spill_px);
}

PixelList StereoSim::RegionPixels(double margin_px, metrics::PanelRegion* region_out,
                                  const metrics::PanelRectangle* drawn, double spill_px) const {
  return CachedRegionPixels(drawn ? *drawn : PanelRectangleOf(truth_.panel), margin_px, spill_px,
                            region_out);
}

PixelList StereoSim::RectanglePixels(const metrics::PanelRectangle& rect, double margin_px,
                                     metrics::PanelRegion* region_out) const {
  return CachedRegionPixels(rect, margin_px, 0.0, region_out);
}

PixelList StereoSim::CachedRegionPixels(const metrics::PanelRectangle& rect, double margin_px,
                                        double spill_px, metrics::PanelRegion* region_out) const {
  // The same rectangle, camera and window give the same region: drawn once, shared.
  static SharedCache<RegionKey, RegionData> cache(kRegionCacheBytes);
  const RegionKey key{rect, params_.sensor.intrinsics, window_, margin_px, spill_px};
  std::shared_ptr<const RegionData> found = cache.Find(key);
  if (!found) {
    auto made = std::make_shared<RegionData>();
    metrics::PanelRectangle grown = rect;
    if (spill_px > 0) {  // region_spill: the region drawn larger
      const Eigen::Vector2d foot = metrics::PixelFootprint(params_.sensor.intrinsics, grown);
      grown.width_m += 2 * spill_px * foot.x();
      grown.height_m += 2 * spill_px * foot.y();
    }
    metrics::PanelRegion region =
        metrics::RegionFromRectangle(params_.sensor.intrinsics, grown, margin_px);
    made->window = PixelsOfImage(&region.pixels).window;
    made->region = std::move(region);
    const std::size_t bytes = sizeof(RegionData) + made->window.size() * (sizeof(int) + 4) +
                              made->region.outline_px.size() * sizeof(Eigen::Vector2d);
    cache.Insert(key, made, bytes);
    found = std::move(made);
  }
  if (region_out) *region_out = found->region;
  PixelList pixels;
  pixels.window = found->window;
  // A region pixel's index in the image is its draw's index in frame 0 (Counter).
  pixels.image.assign(found->region.pixels.begin(), found->region.pixels.end());
  return pixels;
}

PixelList StereoSim::PixelsOfImage(std::vector<std::uint32_t>* image_pixels) const {
  const int width = params_.sensor.intrinsics.width;
  PixelList pixels;
  pixels.window.reserve(image_pixels->size());
  pixels.image.reserve(image_pixels->size());
  std::size_t kept = 0;
  std::uint32_t row_start = 1, row_end = 0;  // [row_start, row_end): the image row of v
  int v = 0;
  for (std::uint32_t i : *image_pixels) {
    if (i < row_start || i >= row_end) {  // the pixels come row after row: one division a row
      const std::uint32_t row = i / static_cast<std::uint32_t>(width);
      row_start = row * static_cast<std::uint32_t>(width);
      row_end = row_start + static_cast<std::uint32_t>(width);
      v = static_cast<int>(row) - window_.v0;
    }
    const int u = static_cast<int>(i - row_start) - window_.u0;
    if (u < 0 || v < 0 || u >= window_.width || v >= window_.height) continue;
    pixels.window.push_back(v * window_.width + u);
    pixels.image.push_back(i);  // a pixel's index in the image is its draw's index in frame 0
    (*image_pixels)[kept++] = i;
  }
  image_pixels->resize(kept);
  return pixels;
}

PixelList StereoSim::PanelPixels(int margin_px) const {
  const int w = window_.width, h = window_.height;
  std::vector<unsigned char> not_panel(static_cast<size_t>(w) * h);
  for (size_t i = 0; i < not_panel.size(); ++i)
    not_panel[i] = surface_[i] != static_cast<unsigned char>(Surface::kPanel);
  const std::vector<unsigned char> eroded_out = Dilate(not_panel, w, h, margin_px);
  PixelList pixels;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const int i = v * w + u;
      // Pixels nearer the window's border than the margin cannot be shown inside the panel.
      if (u < margin_px || v < margin_px || u >= w - margin_px || v >= h - margin_px) continue;
      if (eroded_out[i]) continue;
      pixels.window.push_back(i);
      pixels.image.push_back(Counter(0, i));
    }
  return pixels;
}

}  // namespace depthbias::sim
