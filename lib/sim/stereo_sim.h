#pragma once
// The simulated D455 of one recording: the scene's true depth by ray casting, the per-pixel
// static maps of the sensor model (disparity, hole probability, edge mixing), and the frames
// drawn from them with counter-based random numbers. The random draw of pixel (u, v) in frame k
// depends only on (seed, recording name, k, v·width + u): a frame rendered whole and the same
// pixels evaluated on the panel's footprint alone (the metrics-only path) are identical, and a
// change of a parameter keeps the draws (common random numbers).

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "metrics/geometry.h"
#include "records/depth_frame.h"
#include "records/panel_metrics.h"
#include "sim/effects.h"
#include "sim/scene.h"
#include "sim/sensor.h"

namespace depthbias::sim {

// Everything a simulation run needs.
struct SimParams {
  ProtocolParams protocol;
  SensorParams sensor;
  Departures departures;  // from the effects (BuildDepartures); none = the base model
  std::uint64_t seed = 1;
  // Each image pixel's disparity quantized on the subpixel lattice shifted by a phase of its
  // own (one of 16 over a step, fixed by the pixel's index: every frame of a pixel on one
  // lattice) and read back from that lattice: a region's median then no longer sits at the one
  // phase of the step the panel's distance gives. A model of what a campaign's placements
  // average over, not of a camera (whose lattice is the same for every pixel).
  bool dither_quantization = false;

  bool IsValid(std::string* why) const;
};

// An image window [u0, u0 + width) × [v0, v0 + height).
struct Window {
  int u0 = 0;
  int v0 = 0;
  int width = 0;
  int height = 0;
};

// Pixels of a window: their indices in the window and in the image (both row-major).
struct PixelList {
  std::vector<int> window;
  std::vector<std::uint64_t> image;
  size_t size() const { return window.size(); }
  bool empty() const { return window.empty(); }
};

// What the recording's scene is, whatever the sensor makes of it.
struct CellTruth {
  PanelPose panel;
  double panel_depth_m = 0;   // true Z of the panel's centre
  double panel_range_m = 0;   // true range of the panel's centre
  double panel_angle_deg = 0; // true off-axis angle of the panel's centre
  ScenarioParams scenario;    // the noise and invalidation used
  bool scenario_listed = false;  // false: the sensor's fallback was used
  std::uint64_t cell_seed = 0;
};

class StereoSim {
 public:
  // Throws std::invalid_argument if params are not valid. Without a window, the whole image.
  // The static maps are built by `threads` threads (they do not depend on it).
  StereoSim(const SimParams& params, const Cell& cell, int threads = 1);
  StereoSim(const SimParams& params, const Cell& cell, const Window& window, int threads = 1);

  const CellTruth& truth() const { return truth_; }
  const Window& window() const { return window_; }
  const SimParams& params() const { return params_; }

  // Frame k (from 0) of the recording: full image size, 0 outside the window. Rows are split
  // over `threads` threads (the pixels do not depend on it).
  void Render(int frame_index, records::DepthFrame* frame, int threads = 1) const;
  // Depth counts of the listed pixels in frame k: the same values Render gives them.
  void RenderPixels(int frame_index, const PixelList& pixels,
                    std::vector<std::uint16_t>* counts) const;
  // The same into counts[0, pixels.size()).
  void RenderPixels(int frame_index, const PixelList& pixels, std::uint16_t* out) const;

  // Window pixels that see the panel, and that still do after eroding it by margin_px.
  PixelList PanelPixels(int margin_px) const;
  // The panel's image region, drawn by the one definition panel_extract uses
  // (metrics::RegionFromRectangle) on rect (null: the true panel's rectangle), grown by the
  // region_spill effect, limited to the window; the region itself in *region when given.
  PixelList RegionPixels(double margin_px, metrics::PanelRegion* region = nullptr,
                         const metrics::PanelRectangle* rect = nullptr) const;
  // The same grown by spill_px in place of the region_spill effect's width.
  PixelList RegionPixels(double margin_px, metrics::PanelRegion* region,
                         const metrics::PanelRectangle* rect, double spill_px) const;
  // The region of rect (metrics::RegionFromRectangle, not grown by region_spill), limited to the
  // window; the region itself in *region when given. Shared between simulations like
  // RegionPixels'.
  PixelList RectanglePixels(const metrics::PanelRectangle& rect, double margin_px,
                            metrics::PanelRegion* region = nullptr) const;
  // True depth Z of a window pixel (0 where nothing is hit).
  double TrueDepth(int pixel) const { return true_depth_m_[pixel]; }

 private:
  void Build();
  PixelList CachedRegionPixels(const metrics::PanelRectangle& rect, double margin_px,
                               double spill_px, metrics::PanelRegion* region) const;
  // The given image pixels (v·width + u, sorted) that lie in the window; those outside it are
  // removed from *image_pixels.
  PixelList PixelsOfImage(std::vector<std::uint32_t>* image_pixels) const;
  std::uint64_t Counter(int frame_index, int pixel) const;  // the draw's index
  std::uint64_t PairHash(std::uint64_t counter) const;

  SimParams params_;
  Cell cell_;
  Window window_;
  int threads_ = 1;
  CellTruth truth_;
  double sigma_px_ = 0;
  const float* gauss_ = nullptr;  // the standard normal table
  double inv_step_ = 32;
  float inv_step_f_ = 32, k_min_f_ = 0, k_end_f_ = 0, sigma_f_ = 0;  // single-precision copies
  int k_min_ = 0;
  int k_max_ = 0;
  // Maps shared between simulations (stereo_sim.cpp's caches), never changed once built: the
  // depth counts of quantized disparity k·step, and the window's ray cast.
  struct CountsTable;
  struct CastMaps;
  std::shared_ptr<const CountsTable> counts_table_;
  std::shared_ptr<const CastMaps> cast_;
  const std::uint16_t* counts_of_k_ = nullptr;  // in counts_table_
  // With dither_quantization: the tables of the shifted lattices, one per phase, and each
  // phase's shift in disparity.
  std::vector<std::shared_ptr<const CountsTable>> dither_tables_;
  std::vector<const std::uint16_t*> dither_counts_;
  std::vector<float> dither_offset_;
  const float* true_depth_m_ = nullptr;         // in cast_
  const unsigned char* surface_ = nullptr;      // in cast_
  // True disparity + static departures (≤ 0: no depth): the cast's disparity when there are
  // none.
  std::shared_ptr<const std::vector<float>> static_disparity_px_;
  std::vector<float> mix_delta_px_;         // strength·(other side − own disparity)
  bool mixing_ = false;                     // edge mixing on: mix_delta_px_ is used
  std::vector<std::uint16_t> valid_threshold_;  // valid if a 12-bit uniform is below it
};

// The seed of one recording: a hash of the run's seed and the recording's name.
std::uint64_t CellSeed(std::uint64_t seed, const std::string& cell_name);

}  // namespace depthbias::sim
