#include "core/files/folder_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <string>

#include "core/util/error.h"
#include "core/files/output_guard.h"
#include "core/files/stale_temporaries.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

std::string Now() {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%d %H:%M:%S UTC", &tm);
  return text;
}

// The holder's line, as it wrote it; "" when unreadable.
std::string ReadHolder(int fd) {
  std::string text(512, '\0');
  const ssize_t n = pread(fd, text.data(), text.size(), 0);
  text.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
  while (!text.empty() && (text.back() == '\n' || text.back() == '\0')) text.pop_back();
  return text;
}

}  // namespace

FolderLock::FolderLock(const fs::path& folder, const std::string& command) {
  const fs::path file = folder / kFileName;
  CheckOutput(file);  // never a file in a dataset's folders (core/files/output_guard.h)
  // A symlink planted at the lock's name is replaced, never followed: the holder line would
  // truncate its target (issue 51, case 11).
  fd_ = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd_ < 0 && errno == ELOOP && ::unlink(file.c_str()) == 0)
    fd_ = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd_ < 0) Fail("{}: cannot create the lock file: {}", file.string(), std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    const std::string holder = ReadHolder(fd_);
    ::close(fd_);
    fd_ = -1;
    if (error == EWOULDBLOCK) {
      Fail("{}: in use by {}; wait for it to finish or write to another folder", folder.string(),
           holder.empty() ? "another hdr4d process" : holder);
    }
    Fail("{}: cannot lock: {}", file.string(), std::strerror(error));
  }
  // The folder is ours now: temporaries its killed writers left (a checkpoint each) go.
  RemoveStaleTemporaries(folder);
  const std::string line =
      command + " (pid " + std::to_string(::getpid()) + ", since " + Now() + ")\n";
  // Best effort: the lock itself is what excludes; the text only names the holder.
  if (::ftruncate(fd_, 0) == 0) {
    [[maybe_unused]] const ssize_t written = ::pwrite(fd_, line.data(), line.size(), 0);
  }
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the flock
}

}  // namespace hdr4d
