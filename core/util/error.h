// Two error tiers (ARCHITECTURE §7): HDR4D_CHECK aborts on a broken invariant (a bug in hdr4d);
// hdr4d::Error is thrown for bad user input and I/O, with a message that names the file and
// the problem, and the CLI turns it into one line on stderr and a non-zero exit.
#pragma once

#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace hdr4d {

// An error the user can fix: a missing file, a bad value, an unwritable folder.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// Throws hdr4d::Error with a fmt-formatted message.
template <typename... Args>
[[noreturn]] void Fail(fmt::format_string<Args...> format, Args&&... args) {
  throw Error(fmt::format(format, std::forward<Args>(args)...));
}

[[noreturn]] inline void CheckFailed(const char* expr, const char* file, int line) {
  std::fprintf(stderr, "hdr4d: internal check failed: %s at %s:%d\n", expr, file, line);
  std::abort();
}

}  // namespace hdr4d

// Invariant check, active in every build type: a failure is a bug, not a user mistake.
#define HDR4D_CHECK(cond) ((cond) ? (void)0 : ::hdr4d::CheckFailed(#cond, __FILE__, __LINE__))
