// RenderProtocol: every recording's frames, in order, the same whatever the threads, equal to
// StereoSim's own frames, with the metrics-only truth; errors from the outputs stop the run.
#include <gtest/gtest.h>

#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/render_protocol.h"

namespace depthbias::sim {
namespace {

SimParams SmallProtocol() {
  SimParams p;
  p.protocol.distances_m = {4, 12};
  p.protocol.angles_deg = {0, 20};
  p.protocol.lights = {"daylight"};
  p.protocol.presets = {"HA"};
  p.protocol.emitters = {false, true};
  p.protocol.frames = 3;
  p.sensor.intrinsics.width = 320;  // a quarter of the D455 image: a fast test
  p.sensor.intrinsics.height = 180;
  p.sensor.intrinsics.fx = p.sensor.intrinsics.fy = 160;
  p.sensor.intrinsics.ppx = 160;
  p.sensor.intrinsics.ppy = 90;
  p.seed = 3;
  return p;
}

// Frames kept in memory per recording, with the calls each output saw.
struct Collected {
  std::mutex mutex;
  std::map<std::string, std::vector<records::DepthFrame>> frames;
  std::map<std::string, int> closed;
};

OpenRecording Collect(Collected* c) {
  return [c](const Cell& cell) {
    {
      std::lock_guard<std::mutex> lock(c->mutex);
      c->frames[cell.name];  // opened
    }
    return RecordingOutput{[c, name = cell.name](const records::DepthFrame& f) {
                             std::lock_guard<std::mutex> lock(c->mutex);
                             c->frames[name].push_back(f);
                           },
                           [c, name = cell.name] {
                             std::lock_guard<std::mutex> lock(c->mutex);
                             ++c->closed[name];
                           }};
  };
}

TEST(RenderProtocol, EveryRecordingInOrderWhateverTheThreads) {
  const SimParams p = SmallProtocol();
  const std::vector<Cell> cells = MakeCells(p.protocol);
  ASSERT_EQ(cells.size(), 8u);
  Collected one;
  const auto done = RenderProtocol(p, MetricsParams{}, 1, Collect(&one));
  ASSERT_EQ(done.size(), cells.size());
  for (size_t i = 0; i < cells.size(); ++i) {
    EXPECT_EQ(done[i].cell.name, cells[i].name);
    EXPECT_TRUE(done[i].truth.metrics.ok()) << cells[i].name;
    const CellMetricsResult alone = SimulateMetrics(p, cells[i]);
    EXPECT_EQ(done[i].truth.metrics.hole_rate_pct, alone.metrics.hole_rate_pct);
    EXPECT_EQ(done[i].truth.truth.panel_depth_m, alone.truth.panel_depth_m);
    const auto& frames = one.frames[cells[i].name];
    ASSERT_EQ(frames.size(), 3u) << cells[i].name;
    EXPECT_EQ(one.closed[cells[i].name], 1);
    const StereoSim sim(p, cells[i]);
    for (int k = 0; k < 3; ++k) {
      records::DepthFrame expected;
      sim.Render(k, &expected);
      EXPECT_EQ(frames[k].frame_number, static_cast<std::uint64_t>(k) + 1);
      EXPECT_TRUE(frames[k].counts == expected.counts) << cells[i].name << " frame " << k;
    }
  }
  // Several recordings at once (3 threads), and several threads per recording (16 threads for
  // 8 recordings: 2 each, frame k + 1 rendered while frame k is written).
  for (int threads : {3, 16}) {
    Collected many;
    RenderProtocol(p, MetricsParams{}, threads, Collect(&many));
    for (const Cell& c : cells) {
      ASSERT_EQ(many.frames[c.name].size(), 3u) << c.name << ", threads " << threads;
      for (int k = 0; k < 3; ++k)
        EXPECT_TRUE(many.frames[c.name][k].counts == one.frames[c.name][k].counts)
            << c.name << " frame " << k << ", threads " << threads;
    }
  }
}

TEST(RenderProtocol, AnOutputErrorStopsTheRunAndIsRethrown) {
  const SimParams p = SmallProtocol();
  const std::string bad = MakeCells(p.protocol)[1].name;
  for (int threads : {1, 2, 16}) {
    std::mutex mutex;
    std::map<std::string, int> opened, closed;
    auto open = [&](const Cell& cell) {
      std::lock_guard<std::mutex> lock(mutex);
      ++opened[cell.name];
      const std::string name = cell.name;
      return RecordingOutput{[name, &bad](const records::DepthFrame& f) {
                               if (name == bad && f.frame_number == 2)
                                 throw std::runtime_error("disk full");
                             },
                             [&, name] {
                               std::lock_guard<std::mutex> lock(mutex);
                               ++closed[name];
                             }};
    };
    try {
      RenderProtocol(p, MetricsParams{}, threads, open);
      ADD_FAILURE() << "no error with " << threads << " threads";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "disk full");
    }
    EXPECT_EQ(closed.count(bad), 0u) << "threads " << threads;
    for (const auto& [name, n] : closed) EXPECT_EQ(n, 1) << name;
    if (threads == 1) {  // one at a time: the first recording done, the second failed, no more
      EXPECT_EQ(opened.size(), 2u);
      EXPECT_EQ(closed.size(), 1u);
    }
  }
}

// Pixels go by pairs of draws sharing a hash: rows whose first draw is odd (an odd image width,
// or a window starting at an odd column) must still draw each pixel as RenderPixels does.
TEST(RenderProtocol, OddWidthsAndWindowsDrawEveryPixelAsRenderPixels) {
  SimParams p = SmallProtocol();
  p.sensor.intrinsics.width = 321;
  p.sensor.intrinsics.height = 181;
  p.sensor.fallback.invalid_prob = 0.3;
  const Cell cell = MakeCells(p.protocol)[0];
  for (const Window w : {Window{0, 0, 321, 181}, Window{101, 40, 77, 51}}) {
    const StereoSim sim(p, cell, w);
    PixelList all;
    for (int v = 0; v < w.height; ++v)
      for (int u = 0; u < w.width; ++u) {
        all.window.push_back(v * w.width + u);
        all.image.push_back(static_cast<std::uint64_t>(w.v0 + v) * 321 + w.u0 + u);
      }
    for (int k : {0, 1}) {
      records::DepthFrame frame;
      sim.Render(k, &frame);
      std::vector<std::uint16_t> expected;
      sim.RenderPixels(k, all, &expected);
      int valid = 0, mismatched = 0;
      for (size_t i = 0; i < all.size(); ++i) {
        const std::uint16_t got = frame.counts[all.image[i]];
        mismatched += got != expected[i];
        valid += got != 0;
      }
      EXPECT_EQ(mismatched, 0) << "window at u0 " << w.u0 << ", frame " << k;
      EXPECT_GT(valid, 0);
    }
  }
}

}  // namespace
}  // namespace depthbias::sim
