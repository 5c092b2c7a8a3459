#include "benchmark/child_process.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <thread>

#include "core/util/error.h"

extern char** environ;

namespace hdr4d::bench {
namespace {

std::string LastErrorLine(const std::filesystem::path& log, std::streamoff from) {
  std::ifstream in(log);
  in.seekg(from);
  std::string line, last, error;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    last = line;
    if (line.rfind("hdr4d: error:", 0) == 0) error = line;
  }
  return error.empty() ? last : error;
}

}  // namespace

std::string ChildResult::Describe() const {
  if (timed_out) return fmt::format("timed out after {:.0f} s", wall_seconds);
  if (cancelled) return "cancelled";
  std::string what = signal ? fmt::format("killed by signal {} ({})", signal, strsignal(signal))
                            : fmt::format("exit code {}", exit_code);
  if (!error_line.empty()) what += ": " + error_line;
  return what;
}

std::filesystem::path SelfExecutable() { return "/proc/self/exe"; }

std::filesystem::path SelfExecutablePath() {
  std::error_code ec;
  std::string self = std::filesystem::read_symlink("/proc/self/exe", ec).string();
  if (ec) Fail("cannot find this executable (/proc/self/exe): {}", ec.message());
  const std::string deleted = " (deleted)";  // the file was replaced since this process started
  if (self.size() > deleted.size() && self.compare(self.size() - deleted.size(), deleted.size(), deleted) == 0)
    self.resize(self.size() - deleted.size());
  return self;
}

std::string ShellQuote(const std::string& arg) {
  if (!arg.empty() && arg.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                            "0123456789-_./=:+,@%") == std::string::npos)
    return arg;
  std::string q = "'";
  for (char c : arg) {
    if (c == '\'') {
      q.append("'\\''");
    } else {
      q.push_back(c);
    }
  }
  q.push_back('\'');
  return q;
}

std::string ShellCommand(const std::vector<std::string>& argv) {
  std::string line;
  for (const std::string& a : argv) {
    if (!line.empty()) line.push_back(' ');
    line.append(ShellQuote(a));
  }
  return line;
}

namespace {

// Opens the log for appending and writes the command line to it; *output_start is where the
// child's output will begin.
int OpenLog(const ChildOptions& options, off_t* output_start) {
  if (options.log.has_parent_path()) std::filesystem::create_directories(options.log.parent_path());
  const int log_fd = open(options.log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (log_fd < 0) Fail("{}: cannot open the log: {}", options.log.string(), std::strerror(errno));
  const off_t log_start = lseek(log_fd, 0, SEEK_END);
  // Logs show the binary's file name, not /proc/self/exe, so a command can be rerun by hand.
  std::vector<std::string> shown = options.argv;
  if (shown[0] == SelfExecutable()) shown[0] = SelfExecutablePath().string();
  const std::string header = "$ " + ShellCommand(shown) + "\n";
  if (write(log_fd, header.data(), header.size()) < 0) {
  }
  *output_start = log_start + static_cast<off_t>(header.size());
  return log_fd;
}

// Everything the child needs, built before fork: after it, only async-signal-safe calls.
struct ExecArgs {
  explicit ExecArgs(const ChildOptions& options) {
    for (const std::string& a : options.argv) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    for (char** e = environ; *e; ++e) {
      const std::string entry = *e;
      const std::string key = entry.substr(0, entry.find('='));
      if (!options.env.count(key)) env_storage.push_back(entry);
    }
    for (const auto& [k, v] : options.env) env_storage.push_back(k + "=" + v);
    for (std::string& e : env_storage) envp.push_back(e.data());
    envp.push_back(nullptr);
  }
  ExecArgs(const ExecArgs&) = delete;
  ExecArgs& operator=(const ExecArgs&) = delete;

  std::vector<char*> argv;
  std::vector<std::string> env_storage;
  std::vector<char*> envp;
};

// Forks and executes the child in its own process group, its output into the log; returns its
// pid once the exec has succeeded, and when it started in *start.
pid_t Spawn(const ChildOptions& options,
            const ExecArgs& exec,
            int log_fd,
            std::chrono::steady_clock::time_point* start) {
  const pid_t parent = getpid();
  // exec failures come back through a close-on-exec pipe: a successful exec closes it empty.
  int exec_pipe[2];
  if (pipe2(exec_pipe, O_CLOEXEC) != 0) {
    close(log_fd);
    Fail("cannot start {}: pipe failed: {}", options.argv[0], std::strerror(errno));
  }
  *start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid < 0) {
    close(log_fd);
    close(exec_pipe[0]);
    close(exec_pipe[1]);
    Fail("cannot start {}: fork failed: {}", options.argv[0], std::strerror(errno));
  }
  if (pid == 0) {
    close(exec_pipe[0]);
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(127);  // the harness died between fork and prctl
    setpgid(0, 0);
    const int null_fd = open("/dev/null", O_RDONLY);
    if (null_fd >= 0) dup2(null_fd, 0);
    dup2(log_fd, 1);
    dup2(log_fd, 2);
    execve(exec.argv[0], exec.argv.data(), exec.envp.data());
    const int error = errno;
    if (write(exec_pipe[1], &error, sizeof error) < 0) {
    }
    _exit(127);
  }
  close(log_fd);
  close(exec_pipe[1]);
  setpgid(pid, pid);  // also from the parent, so kill(-pid) works at once
  int exec_error = 0;
  ssize_t got;
  do {
    got = read(exec_pipe[0], &exec_error, sizeof exec_error);
  } while (got < 0 && errno == EINTR);
  close(exec_pipe[0]);
  if (got == static_cast<ssize_t>(sizeof exec_error)) {
    int status = 0;
    waitpid(pid, &status, 0);
    Fail("cannot execute {}: {}", options.argv[0], std::strerror(exec_error));
  }
  return pid;
}

// Waits for the child, stopping its process group on timeout or cancellation (SIGKILL 3 s
// after the stop signal); fills *status and *usage, and the result's timed_out and cancelled.
void Wait(pid_t pid,
          const ChildOptions& options,
          std::chrono::steady_clock::time_point start,
          int* status,
          rusage* usage,
          ChildResult* result) {
  bool stopping = false;
  std::chrono::steady_clock::time_point stop_sent;
  for (;;) {
    const pid_t done = wait4(pid, status, WNOHANG, usage);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) Fail("waiting for {} failed: {}", options.argv[0], std::strerror(errno));
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - start).count();
    if (!stopping) {
      if (options.timeout_seconds > 0 && elapsed > options.timeout_seconds)
        result->timed_out = true;
      if (options.cancel && options.cancel->load()) result->cancelled = true;
      if (result->timed_out || result->cancelled) {
        kill(-pid, options.stop_signal);
        stopping = true;
        stop_sent = now;
      }
    } else if (now - stop_sent > std::chrono::seconds(3)) {
      kill(-pid, SIGKILL);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(stopping ? 20 : 50));
  }
}

}  // namespace

ChildResult RunChild(const ChildOptions& options) {
  if (options.argv.empty()) Fail("RunChild: no program given");
  off_t output_start = 0;
  const int log_fd = OpenLog(options, &output_start);
  const ExecArgs exec(options);
  std::chrono::steady_clock::time_point start;
  const pid_t pid = Spawn(options, exec, log_fd, &start);
  ChildResult result;
  int status = 0;
  rusage usage{};
  Wait(pid, options, start, &status, &usage, &result);
  result.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.peak_rss_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux: kilobytes
  if (WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
  result.error_line = LastErrorLine(options.log, output_start);
  return result;
}

}  // namespace hdr4d::bench
