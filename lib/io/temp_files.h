#pragma once
// Temporary files of a run (a bag's PATH.part, an output's .NAME.tmp.XXXXXX) are registered
// while they exist, so that an interrupted run leaves none: after InstallSignalCleanup(),
// SIGINT, SIGTERM and SIGHUP remove every registered file and then end the process as the
// signal would (exit status 128 + signal in a shell). The handler only calls unlink(), which is
// async-signal-safe.

#include <string>

namespace depthbias::io {

// Registers / unregisters a temporary file (called by io's writers). Up to 4096 registrations
// per process are covered; later ones are not removed on a signal.
void RegisterTempFile(const std::string& path);
void UnregisterTempFile(const std::string& path);

// Installs the handlers (once; later calls do nothing).
void InstallSignalCleanup();

// While a CommitScope lives, a signal waits: the renames that put a run's outputs in place all
// complete, then the process ends by the signal. Outputs are all or none, signals included.
class CommitScope {
 public:
  CommitScope();
  ~CommitScope();
  CommitScope(const CommitScope&) = delete;
  CommitScope& operator=(const CommitScope&) = delete;
};

// The signal that arrived during the run, or 0 (for callers that stop work between steps).
int PendingSignal();

}  // namespace depthbias::io
