#pragma once
// A FrameSource that reads ahead on its own thread, so that reading the recording and measuring
// it run on two cores. Frame buffers are recycled; memory is bounded by depth frames.

#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "panel/extract.h"

namespace depthbias::panel {

class PrefetchSource : public FrameSource {
 public:
  // inner must outlive this object; depth ≥ 1 frames are read ahead.
  PrefetchSource(FrameSource* inner, int depth);
  ~PrefetchSource() override;
  PrefetchSource(const PrefetchSource&) = delete;
  PrefetchSource& operator=(const PrefetchSource&) = delete;

  // Rethrows, in the caller's thread, whatever the inner source threw.
  bool Next(records::DepthFrame* frame) override;
  bool Rewind() override;

 private:
  void Start();
  void Stop();
  void Run();

  FrameSource* inner_;
  std::size_t depth_;
  std::thread thread_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<records::DepthFrame> ready_;
  std::vector<records::DepthFrame> spare_;
  bool done_ = false;
  bool stop_ = false;
  std::exception_ptr error_;
};

}  // namespace depthbias::panel
