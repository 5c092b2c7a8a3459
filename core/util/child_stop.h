// Stopping a child process (COLMAP, Blender) with hdr4d: while one runs, SIGINT, SIGTERM and
// SIGHUP are recorded instead of ending hdr4d, so that the caller stops the child first and
// then fails with a line that says so; the child is started with PR_SET_PDEATHSIG by its caller,
// so kill -9 of hdr4d takes it too. Used by calibration/colmap_process.cpp and
// datagen/blender_process.cpp.
#pragma once

#include <sys/types.h>

#include <csignal>
#include <string>

namespace hdr4d {

// While alive, the three stop signals are recorded (StopSignal()) instead of acted on; the old
// handlers come back when it goes. One at a time per process.
class StopSignals {
 public:
  StopSignals();
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  // The stop signal received since construction, or 0.
  static int StopSignal();

 private:
  static constexpr int kSignals[3] = {SIGINT, SIGTERM, SIGHUP};
  struct sigaction old_[3];
};

// In a child just forked from `parent`, before it execs: it gets SIGKILL when the parent dies
// (kill -9 included; it ends at once if the parent is already gone), reads /dev/null and writes
// stdout and stderr into `out_fd`. Async-signal-safe calls only.
void TieChildToParent(pid_t parent, int out_fd);

// SIGTERM, then SIGKILL when the child has not gone within 3 s; reaps it and returns its status.
int StopChild(pid_t pid);

// Throws hdr4d::Error "interrupted by SIGTERM while <program> ran; it was stopped".
[[noreturn]] void FailInterrupted(int signal, const std::string& program);

}  // namespace hdr4d
