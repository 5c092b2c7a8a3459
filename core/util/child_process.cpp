#include "core/util/child_process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <thread>

#include "core/util/child_stop.h"
#include "core/util/error.h"

extern char** environ;

namespace hdr4d {
namespace fs = std::filesystem;

int RunLoggedChild(const std::vector<std::string>& argv, const std::vector<std::string>& extra_env,
                   const fs::path& log) {
  HDR4D_CHECK(!argv.empty());
  // Everything the child needs is prepared before fork: after it, only async-signal-safe calls.
  std::vector<std::string> env_strings;
  for (char** e = environ; *e; ++e) env_strings.emplace_back(*e);
  env_strings.insert(env_strings.end(), extra_env.begin(), extra_env.end());
  std::vector<char*> envp, args;
  for (std::string& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::vector<std::string> argv_copy = argv;
  for (std::string& s : argv_copy) args.push_back(s.data());
  args.push_back(nullptr);
  const int log_fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (log_fd < 0) Fail("{}: cannot create the log ({})", log.string(), std::strerror(errno));

  StopSignals stop;
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    close(log_fd);
    Fail("{}: cannot start ({})", argv[0], std::strerror(errno));
  }
  if (pid == 0) {
    TieChildToParent(parent, log_fd);
    execvpe(args[0], args.data(), envp.data());
    _exit(127);
  }
  close(log_fd);
  int status = 0;
  for (;;) {
    const pid_t done = waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) Fail("{}: waiting for it failed ({})", argv[0], std::strerror(errno));
    if (const int signal = StopSignals::StopSignal()) {
      StopChild(pid);
      FailInterrupted(signal, argv[0]);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

std::string LastLogLine(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  return last;
}

fs::path MakePrivateTempFolder(const std::string& prefix) {
  std::string pattern = (fs::temp_directory_path() / (prefix + "XXXXXX")).string();
  if (!mkdtemp(pattern.data())) Fail("{}: cannot create a private folder ({})", pattern, std::strerror(errno));
  return pattern;
}

}  // namespace hdr4d
