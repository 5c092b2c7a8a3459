#include "datagen/blender_process.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <sstream>
#include <thread>

#include "core/util/child_stop.h"
#include "core/util/error.h"

extern char** environ;

namespace hdr4d::datagen {
namespace fs = std::filesystem;

namespace {

bool IsExecutableFile(const fs::path& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec) && access(path.c_str(), X_OK) == 0;
}

std::string EnvOrEmpty(const char* name) {
  const char* value = std::getenv(name);
  return value == nullptr ? "" : value;
}

fs::path CheckedExecutable(const std::string& path, const char* origin) {
  if (!IsExecutableFile(path)) {
    Fail("{}: Blender not found or not executable (from {})", path, origin);
  }
  return fs::absolute(path);
}

}  // namespace

fs::path FindBlender(const std::string& explicit_path) {
  if (!explicit_path.empty()) return CheckedExecutable(explicit_path, "--blender");
  const std::string from_env = EnvOrEmpty("HDR4D_BLENDER");
  if (!from_env.empty()) return CheckedExecutable(from_env, "$HDR4D_BLENDER");
  std::stringstream path_list(EnvOrEmpty("PATH"));
  std::string dir;
  while (std::getline(path_list, dir, ':')) {
    if (dir.empty()) continue;
    const fs::path candidate = fs::path(dir) / "blender";
    if (IsExecutableFile(candidate)) return candidate;
  }
  Fail(
      "blender: not found on PATH; install it with `bash scripts/install-deps.sh` (Debian "
      "package blender), or pass --blender PATH or set HDR4D_BLENDER");
}

fs::path FindScriptsDir(const std::string& explicit_dir) {
  std::string dir = explicit_dir;
  const char* origin = "--scripts-dir";
  if (dir.empty()) {
    dir = EnvOrEmpty("HDR4D_DATAGEN_DIR");
    origin = "$HDR4D_DATAGEN_DIR";
  }
  if (dir.empty()) {
    dir = HDR4D_DATAGEN_SCRIPTS_DIR;
    origin = "the source tree";
  }
  const fs::path script = fs::path(dir) / kRenderScript;
  std::error_code ec;
  if (!fs::is_regular_file(script, ec)) {
    Fail(
        "{}: the datagen Blender scripts are not there (folder from {}; set --scripts-dir or "
        "HDR4D_DATAGEN_DIR to datagen/blender)",
        script.string(), origin);
  }
  return fs::absolute(dir);
}

std::string ProcessResult::Describe() const {
  return signal > 0 ? "signal " + std::to_string(signal) : "exit code " + std::to_string(exit_code);
}

namespace {

// Starts argv with stdin from /dev/null and stdout and stderr into `out_fd`. fork, not
// posix_spawn, for PR_SET_PDEATHSIG: the child gets SIGKILL when hdr4d dies, even by SIGKILL
// (the signal follows the thread that forks; Blender runs from the calling thread, which waits
// for it). After fork only async-signal-safe calls; an exec failure comes back through a pipe.
pid_t StartChild(const std::vector<std::string>& argv, int out_fd) {
  std::vector<std::string> argv_copy = argv;
  std::vector<char*> args;
  for (std::string& a : argv_copy) args.push_back(a.data());
  args.push_back(nullptr);
  int exec_error[2];
  if (pipe2(exec_error, O_CLOEXEC) != 0)
    Fail("{}: cannot create a pipe: {}", argv[0], strerror(errno));
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid == 0) {
    TieChildToParent(parent, out_fd);
    execve(args[0], args.data(), environ);
    const int e = errno;
    [[maybe_unused]] const ssize_t n = write(exec_error[1], &e, sizeof e);
    _exit(127);
  }
  const int fork_error = errno;
  close(exec_error[1]);
  int child_errno = 0;
  ssize_t n;
  while ((n = read(exec_error[0], &child_errno, sizeof child_errno)) < 0 && errno == EINTR) {
  }
  close(exec_error[0]);
  if (pid < 0) Fail("{}: cannot run: {}", argv[0], strerror(fork_error));
  if (n > 0) {
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    Fail("{}: cannot run: {}", argv[0], strerror(child_errno));
  }
  return pid;
}

}  // namespace

ProcessResult RunProcess(const std::vector<std::string>& argv,
                         const std::function<void(const std::string&)>& on_line) {
  HDR4D_CHECK(!argv.empty());
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) Fail("{}: cannot create a pipe: {}", argv[0], strerror(errno));
  StopSignals stop;
  pid_t pid = -1;
  try {
    pid = StartChild(argv, fds[1]);
  } catch (...) {
    close(fds[0]);
    close(fds[1]);
    throw;
  }
  close(fds[1]);

  std::string pending;
  char buffer[4096];
  std::exception_ptr callback_error;
  int stop_signal = 0;
  for (;;) {
    // Polled, so that a stop signal is seen while the child prints nothing.
    if ((stop_signal = StopSignals::StopSignal()) != 0) break;
    pollfd ready{.fd = fds[0], .events = POLLIN, .revents = 0};
    const int polled = poll(&ready, 1, 100);
    if (polled == 0 || (polled < 0 && errno == EINTR)) continue;
    const ssize_t n = read(fds[0], buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    pending.append(buffer, static_cast<std::size_t>(n));
    std::size_t start = 0, end;
    try {
      while ((end = pending.find('\n', start)) != std::string::npos) {
        on_line(pending.substr(start, end - start));
        start = end + 1;
      }
    } catch (...) {
      callback_error = std::current_exception();
      break;
    }
    pending.erase(0, start);
  }
  close(fds[0]);
  if (!callback_error && stop_signal == 0 && !pending.empty()) {
    try {
      on_line(pending);
    } catch (...) {
      callback_error = std::current_exception();
    }
  }

  int status = 0;
  if (callback_error || stop_signal != 0) {
    status = StopChild(pid);  // the caller gave up on it, or hdr4d is asked to stop
  } else {
    for (;;) {  // its output has ended; a stop signal still stops it
      const pid_t done = waitpid(pid, &status, WNOHANG);
      if (done == pid) break;
      if (done < 0 && errno != EINTR)
        Fail("{}: waiting for the process failed: {}", argv[0], strerror(errno));
      if ((stop_signal = StopSignals::StopSignal()) != 0) {
        status = StopChild(pid);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  if (callback_error) std::rethrow_exception(callback_error);
  if (stop_signal != 0) FailInterrupted(stop_signal, argv[0]);
  ProcessResult result;
  if (WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
  return result;
}

}  // namespace hdr4d::datagen
