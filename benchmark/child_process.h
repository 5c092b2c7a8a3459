// Runs one hdr4d command (or any program) as a child process, the way the harness runs every
// training, render and scene generation: isolated, with its output in a log file, a wall-clock
// limit, cancellation, and its peak memory. The child gets its own process group (so Blender
// under `hdr4d datagen` is stopped with it) and dies with the harness (PR_SET_PDEATHSIG), so a
// killed harness leaves no orphan training behind.
#pragma once

#include <atomic>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace hdr4d::bench {

struct ChildOptions {
  std::vector<std::string> argv;  // argv[0] is the program (a path)
  std::filesystem::path log;      // stdout and stderr are appended here
  double timeout_seconds = 0;     // 0 = none
  const std::atomic<bool>* cancel = nullptr;  // when it becomes true, the child is stopped
  int stop_signal = 15;  // sent on cancel or timeout (SIGTERM; SIGKILL follows after 3 s)
  std::map<std::string, std::string> env;     // added to the environment
};

struct ChildResult {
  int exit_code = -1;  // when it exited by itself
  int signal = 0;      // the signal that ended it, else 0
  bool timed_out = false;
  bool cancelled = false;
  double wall_seconds = 0;
  double peak_rss_mb = 0;
  bool ok() const { return exit_code == 0 && signal == 0; }
  // "exit code 1: hdr4d: error: ...", "killed by signal 9", "timed out after 60 s", ...
  std::string Describe() const;
  std::string error_line;  // the last "hdr4d: error:" line of the log (or its last line)
};

// Throws hdr4d::Error only when the child cannot be started (fork fails, the program cannot
// be executed, the log is not writable): a harness problem, not a failed run.
ChildResult RunChild(const ChildOptions& options);

// The harness runs its own binary for every step: "/proc/self/exe", which stays this exact
// binary even when a rebuild replaces the file (the children then keep the code version the
// runs were planned with).
std::filesystem::path SelfExecutable();
// The file name of this binary, for scripts that run it later (Slurm).
std::filesystem::path SelfExecutablePath();

// The command as one shell-quoted line (for logs and Slurm scripts).
std::string ShellQuote(const std::string& arg);
std::string ShellCommand(const std::vector<std::string>& argv);

}  // namespace hdr4d::bench
