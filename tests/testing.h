// Shared helpers for every test: a fresh temporary folder per test, the real data under
// ../shared/data, and running the hdr4d binary.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "core/util/error.h"
#include "core/image/image.h"

namespace hdr4d::testing {

// A new empty folder, removed when the object goes out of scope.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// The repository root.
std::filesystem::path SourceDir();
// ../shared/data/<name> next to the repository, or nullopt when it is not there (tests that need
// it call GTEST_SKIP with a reason).
std::optional<std::filesystem::path> SharedData(const std::string& name);

// The hdr4d binary these tests run.
std::string Hdr4dBinary();

// Runs `hdr4d <args>` and captures its exit code, stdout and stderr.
struct CommandResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};
CommandResult RunHdr4d(const std::string& args);
// The same with a command in front (e.g. "setpriv --reuid=65534 ..." to run as another user).
CommandResult RunHdr4dWith(const std::string& prefix, const std::string& args);

// An image filled with a deterministic pseudo-random pattern in [lo, hi).
Image RandomImage(int width,
                  int height,
                  int channels,
                  unsigned seed,
                  float lo = 0.0f,
                  float hi = 1.0f,
                  Encoding encoding = Encoding::kLinear);

void WriteTextFile(const std::filesystem::path& path, const std::string& text);

// The message of the hdr4d::Error that `fn` throws, or "" when it throws none.
template <typename Fn>
std::string ErrorOf(Fn&& fn) {
  try {
    fn();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}
std::string ReadTextFile(const std::filesystem::path& path);

}  // namespace hdr4d::testing
