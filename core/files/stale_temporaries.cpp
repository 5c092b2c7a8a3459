#include "core/files/stale_temporaries.h"

#include <signal.h>
#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <string>
#include <system_error>

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

// The writer's pid of a name ".<target>.tmp-<pid>-<n>", or -1 when the name is not one.
long TemporaryOwner(const std::string& name) {
  if (name.size() < 2 || name[0] != '.') return -1;
  const std::size_t tag = name.rfind(".tmp-");
  if (tag == std::string::npos || tag == 0) return -1;
  const std::size_t dash = name.find('-', tag + 5);
  if (dash == std::string::npos || dash + 1 >= name.size()) return -1;
  long pid = -1, n = -1;
  const char* first = name.data() + tag + 5;
  const char* mid = name.data() + dash;
  if (auto r = std::from_chars(first, mid, pid); r.ec != std::errc() || r.ptr != mid) return -1;
  const char* last = name.data() + name.size();
  if (auto r = std::from_chars(mid + 1, last, n); r.ec != std::errc() || r.ptr != last) return -1;
  return pid > 0 ? pid : -1;
}

bool ProcessGone(long pid) { return ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH; }

}  // namespace

int RemoveStaleTemporaries(const fs::path& folder) {
  int removed = 0;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const long pid = TemporaryOwner(it->path().filename().string());
    if (pid < 0 || pid == ::getpid() || !ProcessGone(pid)) continue;
    std::error_code rec;
    if (!it->is_symlink(rec) && !it->is_regular_file(rec)) continue;
    if (fs::remove(it->path(), rec)) ++removed;
  }
  return removed;
}

}  // namespace hdr4d
