#include "sim/render_protocol.h"

#include <algorithm>
#include <future>

#include "sim/parallel.h"

namespace depthbias::sim {
namespace {

// One recording into its output; `threads` threads render each frame.
void RenderRecording(const SimParams& params, const Cell& cell, int threads,
                     const RecordingOutput& out) {
  // Building the static maps is serial within a recording: with one thread per recording, the
  // cores are kept busy by recordings.
  const StereoSim simulator(params, cell, threads);
  camera::DepthFrame frames[2];
  const int n = params.protocol.frames;
  if (threads < 2) {
    for (int k = 0; k < n; ++k) {
      simulator.Render(k, &frames[0]);
      out.write(frames[0]);
    }
  } else {
    simulator.Render(0, &frames[0], threads);
    for (int k = 0; k < n; ++k) {
      // If write throws, the future's destructor waits for the render in flight (std::async).
      std::future<void> next;
      if (k + 1 < n)
        next = std::async(std::launch::async,
                          [&, k] { simulator.Render(k + 1, &frames[(k + 1) % 2], threads); });
      out.write(frames[k % 2]);
      if (next.valid()) next.get();
    }
  }
  out.close();
}

}  // namespace

std::vector<RenderedRecording> RenderProtocol(const SimParams& params,
                                              const MetricsParams& metrics, int threads,
                                              const OpenRecording& open) {
  const std::vector<Cell> cells = MakeCells(params.protocol);
  std::vector<RenderedRecording> done(cells.size());
  threads = std::max(1, threads);
  const int workers = std::min<int>(threads, std::max<int>(1, static_cast<int>(cells.size())));
  const int per_recording = std::max(1, threads / workers);
  detail::ForEachIndex(cells.size(), workers, [&](size_t i) {
    RenderRecording(params, cells[i], per_recording, open(cells[i]));
    done[i].cell = cells[i];
    done[i].truth = SimulateMetrics(params, cells[i], metrics);
  });
  return done;
}

}  // namespace depthbias::sim
