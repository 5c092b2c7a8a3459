// Running a program (a COLMAP step, ffmpeg) as a child process that cannot outlive hdr4d: its own
// argv (no shell), output to a log file, killed with hdr4d (PR_SET_PDEATHSIG on kill -9) and
// stopped when hdr4d gets SIGTERM, SIGINT or SIGHUP (issue 51 §21), after which the caller's
// error path removes what it staged.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace hdr4d {

// Runs argv[0] (searched in PATH when it has no slash) with `extra_env` ("NAME=value") added
// and stdout+stderr in `log`; returns its exit code (127: it could not be executed). Throws
// hdr4d::Error when it cannot be started, and "interrupted by SIGTERM" (etc.) after stopping
// the child when this process is asked to stop while waiting.
int RunLoggedChild(const std::vector<std::string>& argv, const std::vector<std::string>& extra_env,
                   const std::filesystem::path& log);

// The last line of a child's log that holds more than blanks ("" when none): what a failure
// message quotes.
std::string LastLogLine(const std::filesystem::path& log);

// A folder only this user can enter, newly made under the temporary directory (mkdtemp: no
// name to predict, no link to follow); where a failed step's log is kept (issue 51 §8).
std::filesystem::path MakePrivateTempFolder(const std::string& prefix);

}  // namespace hdr4d
