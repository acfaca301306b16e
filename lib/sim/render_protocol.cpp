#include "sim/render_protocol.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <future>
#include <mutex>

#include "common/parallel.h"

namespace depthbias::sim {
namespace {

// One recording into its output; `threads` threads build its static maps and render each frame.
// Returns false, without closing the output, when `stop` is raised between two frames.
bool RenderRecording(const SimParams& params, const Cell& cell, int threads,
                     const RecordingOutput& out, const std::atomic<bool>& stop) {
  const StereoSim simulator(params, cell, threads);
  records::DepthFrame frames[2];
  const int n = params.protocol.frames;
  if (threads < 2) {
    for (int k = 0; k < n; ++k) {
      if (stop) return false;
      simulator.Render(k, &frames[0]);
      out.write(frames[0]);
    }
  } else {
    simulator.Render(0, &frames[0], threads);
    for (int k = 0; k < n; ++k) {
      if (stop) return false;
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
  return true;
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
  // The first error raises `stop`: recordings under way are left unclosed, none is started.
  std::atomic<bool> stop{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  common::ForEachIndex(cells.size(), workers, [&](size_t i) {
    if (stop) return;
    try {
      if (!RenderRecording(params, cells[i], per_recording, open(cells[i]), stop)) return;
      done[i].cell = cells[i];
      done[i].truth = SimulateMetrics(params, cells[i], metrics);
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      stop = true;
    }
  });
  if (error) std::rethrow_exception(error);
  return done;
}

}  // namespace depthbias::sim
