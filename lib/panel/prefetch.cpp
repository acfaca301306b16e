#include "panel/prefetch.h"

#include <utility>

namespace depthbias::panel {

PrefetchSource::PrefetchSource(FrameSource* inner, int depth)
    : inner_(inner), depth_(depth < 1 ? 1 : static_cast<std::size_t>(depth)) {
  Start();
}

PrefetchSource::~PrefetchSource() { Stop(); }

void PrefetchSource::Start() {
  done_ = stop_ = false;
  error_ = nullptr;
  thread_ = std::thread([this] { Run(); });
}

void PrefetchSource::Stop() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  for (auto& f : ready_) spare_.push_back(std::move(f));
  ready_.clear();
}

void PrefetchSource::Run() {
  for (;;) {
    records::DepthFrame frame;
    {
      std::unique_lock<std::mutex> lock(mu_);
      cv_.wait(lock, [&] { return stop_ || ready_.size() < depth_; });
      if (stop_) return;
      if (!spare_.empty()) {
        frame = std::move(spare_.back());
        spare_.pop_back();
      }
    }
    bool got = false;
    std::exception_ptr error;
    try {
      got = inner_->Next(&frame);
    } catch (...) {
      error = std::current_exception();
    }
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (got) {
        ready_.push_back(std::move(frame));
      } else {
        done_ = true;
        error_ = error;
      }
    }
    cv_.notify_all();
    if (!got) return;
  }
}

bool PrefetchSource::Next(records::DepthFrame* frame) {
  std::unique_lock<std::mutex> lock(mu_);
  cv_.wait(lock, [&] { return !ready_.empty() || done_; });
  if (ready_.empty()) {
    if (error_) std::rethrow_exception(error_);
    return false;
  }
  std::swap(*frame, ready_.front());
  // The caller's previous buffer, now in the front slot, is kept for the reader to refill.
  if (spare_.size() < depth_ && !ready_.front().counts.empty())
    spare_.push_back(std::move(ready_.front()));
  ready_.pop_front();
  lock.unlock();
  cv_.notify_all();
  return true;
}

bool PrefetchSource::Rewind() {
  Stop();
  if (!inner_->Rewind()) return false;
  Start();
  return true;
}

}  // namespace depthbias::panel
