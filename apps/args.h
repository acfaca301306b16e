#pragma once
// The command line of an app, walked flag by flag. Mistakes throw std::invalid_argument with a
// one-line message naming the flag; numbers are checked whole ("2abc", "nan", "1e999" and
// out-of-range values are refused, never read as a prefix or clamped).

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

namespace depthbias::apps {

constexpr double kNoLimit = std::numeric_limits<double>::infinity();

// The number `text` (given for `flag`) holds: all of it a finite number in
// [min_value, max_value], a whole one if `whole`.
inline double FlagNumber(const std::string& flag, const std::string& text, bool whole,
                         double min_value, double max_value = kNoLimit) {
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v) || v < min_value ||
      v > max_value || (whole && v != std::floor(v))) {
    auto num = [](double x) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.10g", x);
      return std::string(buf);
    };
    const std::string range = std::isinf(min_value) && std::isinf(max_value) ? ""
                              : std::isinf(max_value) ? " >= " + num(min_value)
                                  : " in [" + num(min_value) + ", " + num(max_value) + "]";
    throw std::invalid_argument(flag + " '" + text + "' is not a " +
                                (whole ? "whole" : "finite") + " number" + range);
  }
  return v;
}

class Args {
 public:
  Args(int argc, char** argv) : argc_(argc), argv_(argv) {}

  // Moves to the next argument; false after the last.
  bool Next() {
    if (++i_ >= argc_) return false;
    flag_ = argv_[i_];
    return true;
  }
  const std::string& flag() const { return flag_; }
  bool IsHelp() const { return flag_ == "--help" || flag_ == "-h"; }

  // The flag's value: the argument after it.
  std::string Value() {
    if (i_ + 1 >= argc_) throw std::invalid_argument(flag_ + " needs a value");
    return argv_[++i_];
  }
  // The flag's value as a number (FlagNumber).
  double Number(bool whole, double min_value, double max_value = kNoLimit) {
    return FlagNumber(flag_, Value(), whole, min_value, max_value);
  }

 private:
  int argc_;
  char** argv_;
  int i_ = 0;
  std::string flag_;
};

// Exit status, the same for every tool.
constexpr int kExitOk = 0;          // everything done, every row ok
constexpr int kExitRowsFailed = 1;  // outputs written, some rows (recordings, bags) failed
constexpr int kExitError = 2;       // nothing written: a usage, input or output error
constexpr char kExitHelp[] =
    "Exit status: 0 all done, every row ok; 1 outputs written, some rows failed;\n"
    "  2 nothing written (usage, input or output error); 128+N ended by signal N (130 for\n"
    "  Ctrl-C, 143 for SIGTERM), its temporary files removed and no output half-written.\n";

// --help: the tool's usage and the exit statuses on stdout; the status to return (kExitOk).
inline int PrintHelp(const char* usage) {
  std::fputs(usage, stdout);
  std::fputs(kExitHelp, stdout);
  return kExitOk;
}

// "32 recordings: 30 ok, 2 no_panel -> metrics.csv": rows counted by status, "ok" first;
// `noun` is singular ("recording"), made plural when total is not 1.
inline std::string Summary(std::size_t total, const std::string& noun,
                           const std::map<std::string, std::size_t>& by_status,
                           const std::string& out) {
  std::string s = std::to_string(total) + " " + noun + (total == 1 ? ":" : "s:");
  std::string sep = " ";
  if (const auto ok = by_status.find("ok"); ok != by_status.end()) {
    s += sep + std::to_string(ok->second) + " ok";
    sep = ", ";
  }
  for (const auto& [status, n] : by_status) {
    if (status == "ok" || n == 0) continue;
    s += sep + std::to_string(n) + " " + status;
    sep = ", ";
  }
  return s + (out.empty() ? "" : " \u2192 " + out);
}

// Progress on stderr when it is a terminal (never in a pipe or a log file): "[k/N] label",
// rewritten in place; Clear() removes it before other lines are printed.
class Progress {
 public:
  explicit Progress(std::size_t total, bool enabled = true)
      : total_(total), on_(enabled && ::isatty(STDERR_FILENO)) {}
  ~Progress() { Clear(); }
  bool on() const { return on_; }
  void Step(const std::string& label) {
    if (!on_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    ++done_;
    std::fprintf(stderr, "\r\033[K[%zu/%zu] %s", done_, total_, label.c_str());
    std::fflush(stderr);
  }
  // A line of its own (a failed row) without tearing the progress line.
  void Line(const std::string& text) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::fprintf(stderr, "%s%s\n", on_ ? "\r\033[K" : "", text.c_str());
  }
  void Clear() {
    if (!on_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    std::fputs("\r\033[K", stderr);
    std::fflush(stderr);
  }

 private:
  std::size_t total_;
  std::size_t done_ = 0;
  bool on_;
  std::mutex mutex_;
};

// For one long library call without steps of its own: "label... 12 s" on a terminal, once a
// second on a thread of its own, until destroyed.
class Ticker {
 public:
  explicit Ticker(std::string label) : label_(std::move(label)) {
    if (!::isatty(STDERR_FILENO)) return;
    thread_ = std::thread([this] {
      const auto start = std::chrono::steady_clock::now();
      std::unique_lock<std::mutex> lock(mutex_);
      while (!stop_) {
        const auto s = std::chrono::duration_cast<std::chrono::seconds>(
                           std::chrono::steady_clock::now() - start)
                           .count();
        std::fprintf(stderr, "\r\033[K%s... %lld s", label_.c_str(), static_cast<long long>(s));
        std::fflush(stderr);
        cv_.wait_for(lock, std::chrono::seconds(1));
      }
      std::fputs("\r\033[K", stderr);
      std::fflush(stderr);
    });
  }
  ~Ticker() {
    if (!thread_.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }

 private:
  std::string label_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace depthbias::apps
