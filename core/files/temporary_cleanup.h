// Temporary files removed when hdr4d is stopped by a signal. SIGINT, SIGTERM and SIGHUP (a
// closed terminal, issue 51 case 19) end the process the same way: the temporary files of the
// writes in flight (core/files/atomic_file.cpp) are unlinked, then the signal is raised again
// with its default action, so the exit status still says which signal it was. kill -9 cannot be
// caught: what it leaves is removed when the folder is next locked (stale_temporaries.h).
#pragma once

#include <filesystem>

namespace hdr4d {

// Installs the handlers (once; the CLI does it for every command, cli/app.cpp).
void RemoveTemporariesOnStopSignals();

// A temporary file to unlink if a stop signal comes before Forget(). Up to a fixed number are
// tracked at once (signal handlers cannot allocate); beyond that a file is not tracked and only
// the next lock of its folder removes it.
class TrackedTemporary {
 public:
  explicit TrackedTemporary(const std::filesystem::path& path);
  ~TrackedTemporary();
  TrackedTemporary(const TrackedTemporary&) = delete;
  TrackedTemporary& operator=(const TrackedTemporary&) = delete;

 private:
  int slot_ = -1;
};

}  // namespace hdr4d
