#include "io/temp_files.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstring>

namespace depthbias::io {
namespace {

// Slots are used once and never freed (a handler may be reading one while another thread
// unregisters it): a path's text never changes while it is visible.
constexpr int kSlots = 4096;
std::atomic<char*> g_paths[kSlots];
std::atomic<bool> g_live[kSlots];
std::atomic<int> g_used{0};
std::atomic<int> g_commit_depth{0};
std::atomic<int> g_pending{0};
std::atomic<bool> g_installed{false};

void RemoveAllAndDie(int sig) {
  const int used = std::min(g_used.load(), kSlots);
  for (int i = 0; i < used; ++i) {
    const char* p = g_paths[i].load();
    if (p && g_live[i].load()) ::unlink(p);
  }
  ::signal(sig, SIG_DFL);
  ::raise(sig);  // delivered when the handler returns (or at once outside a handler)
}

void OnSignal(int sig) {
  g_pending.store(sig);
  if (g_commit_depth.load() > 0) return;  // the commit finishes first
  RemoveAllAndDie(sig);
}

}  // namespace

void RegisterTempFile(const std::string& path) {
  const int i = g_used.fetch_add(1);
  if (i >= kSlots) return;
  g_paths[i].store(::strdup(path.c_str()));
  g_live[i].store(true);
}

void UnregisterTempFile(const std::string& path) {
  const int used = std::min(g_used.load(), kSlots);
  for (int i = 0; i < used; ++i) {
    const char* p = g_paths[i].load();
    if (p && g_live[i].load() && path == p) {
      g_live[i].store(false);
      return;
    }
  }
}

void InstallSignalCleanup() {
  if (g_installed.exchange(true)) return;
  struct sigaction sa {};
  sa.sa_handler = OnSignal;
  sigemptyset(&sa.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    // A signal the parent ignores (nohup, a shell's background job) stays ignored.
    if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    ::sigaction(sig, &sa, nullptr);
  }
}

CommitScope::CommitScope() { g_commit_depth.fetch_add(1); }

CommitScope::~CommitScope() {
  if (g_commit_depth.fetch_sub(1) == 1 && g_pending.load() != 0) RemoveAllAndDie(g_pending.load());
}

int PendingSignal() { return g_pending.load(); }

}  // namespace depthbias::io
