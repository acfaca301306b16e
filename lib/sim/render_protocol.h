#pragma once
// Every recording of a protocol rendered frame by frame into outputs the caller opens (the
// simulate app opens RealSense bags through io): recordings run on parallel threads, each
// recording's frames in order, and each recording's truth comes from the metrics-only path on
// the same draws.

#include <functional>
#include <vector>

#include "records/depth_frame.h"
#include "sim/sim_metrics.h"
#include "sim/stereo_sim.h"

namespace depthbias::sim {

// Where one recording's frames go. Both are called on the thread rendering the recording.
struct RecordingOutput {
  std::function<void(const records::DepthFrame&)> write;  // frame by frame, in order
  std::function<void()> close;                            // after the last frame
};
// Opens the output of a recording; called on the thread that will render it.
using OpenRecording = std::function<RecordingOutput(const Cell&)>;

struct RenderedRecording {
  Cell cell;
  CellMetricsResult truth;  // the metrics-only result: true pose, depth, hole rate
};

// The protocol's recordings, in MakeCells' order. `threads` threads share the recordings; with
// more threads than recordings, a recording renders its frames on several threads, frame k + 1
// while frame k is written. The frames do not depend on the threads. An exception from
// rendering, open, write or close stops the run: recordings under way stop between two frames
// without their close being called (their outputs are dropped unclosed: the app's bag writers
// then remove their partial files), and the first exception is rethrown. Recordings finished
// before it stay closed.
std::vector<RenderedRecording> RenderProtocol(const SimParams& params,
                                              const MetricsParams& metrics, int threads,
                                              const OpenRecording& open);

}  // namespace depthbias::sim
