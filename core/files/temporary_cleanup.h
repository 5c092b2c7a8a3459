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

// A temporary file to unlink if a stop signal comes before it is released. A fixed number of
// slots, then nodes of a list made before any signal (signal handlers cannot allocate), so every
// temporary is tracked however many are pending (a video's frames wait for one commit).
class TrackedTemporary {
 public:
  explicit TrackedTemporary(const std::filesystem::path& path);
  ~TrackedTemporary();
  TrackedTemporary(const TrackedTemporary&) = delete;
  TrackedTemporary& operator=(const TrackedTemporary&) = delete;

 private:
  int slot_ = -1;
  void* overflow_ = nullptr;  // a node of the list beyond the slots (temporary_cleanup.cpp)
};

}  // namespace hdr4d
