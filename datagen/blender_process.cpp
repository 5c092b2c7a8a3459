#include "datagen/blender_process.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <sstream>

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

ProcessResult RunProcess(const std::vector<std::string>& argv,
                         const std::function<void(const std::string&)>& on_line) {
  HDR4D_CHECK(!argv.empty());
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) Fail("{}: cannot create a pipe: {}", argv[0], strerror(errno));

  // posix_spawn, not fork: safe in a process that already runs worker threads.
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int spawn_error =
      posix_spawn(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[1]);
  if (spawn_error != 0) {
    close(fds[0]);
    Fail("{}: cannot run: {}", argv[0], strerror(spawn_error));
  }

  std::string pending;
  char buffer[4096];
  std::exception_ptr callback_error;
  for (;;) {
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
  if (!callback_error && !pending.empty()) {
    try {
      on_line(pending);
    } catch (...) {
      callback_error = std::current_exception();
    }
  }

  if (callback_error) kill(pid, SIGTERM);  // the caller gave up on it; do not wait for a render
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) Fail("{}: waiting for the process failed: {}", argv[0], strerror(errno));
  }
  if (callback_error) std::rethrow_exception(callback_error);
  ProcessResult result;
  if (WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
  return result;
}

}  // namespace hdr4d::datagen
