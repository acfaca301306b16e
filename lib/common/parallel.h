#pragma once
// The one parallel-for of the library and the apps. ForEachIndex runs f(i) for i in [0, n) on up
// to `threads` threads, each taking the next index; ForEachBand splits [0, n) into `threads`
// contiguous bands. The first exception stops the hand-out and is rethrown once every thread has
// finished; when no more threads can be had, fewer workers do the work. Results never depend on
// the thread count: each index is handled by exactly one call.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace depthbias::common {

template <typename F>
void ForEachIndex(std::size_t n, int threads, F f) {
  threads = std::max(1, static_cast<int>(std::min<std::size_t>(std::max(threads, 1), n)));
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&] {
    try {
      for (std::size_t i = next++; i < n; i = next++) f(i);
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      next = n;
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) {
    try {
      pool.emplace_back(work);
    } catch (const std::system_error&) {  // no more threads to be had: fewer workers
      break;
    }
  }
  work();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

// f(begin, end) over `threads` contiguous bands of [0, n).
template <typename F>
void ForEachBand(std::size_t n, int threads, F f) {
  const std::size_t bands = std::max<std::size_t>(1, std::min<std::size_t>(std::max(threads, 1), n));
  ForEachIndex(bands, static_cast<int>(bands),
               [&](std::size_t b) { f(n * b / bands, n * (b + 1) / bands); });
}

}  // namespace depthbias::common
