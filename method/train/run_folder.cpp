#include "method/train/run_folder.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <exception>
#include <vector>

#include "core/files/folder_lock.h"
#include "core/files/output_guard.h"
#include "core/util/error.h"

namespace hdr4d::method {
namespace fs = std::filesystem;

namespace {

bool Present(const fs::path& path) {
  std::error_code ec;
  return fs::symlink_status(path, ec).type() != fs::file_type::not_found && !ec;
}

// Whether another writer holds RUN's lock now (then it, not the files it is writing, is what
// this run is told about when it takes the lock).
bool LockHeldByAnother(const fs::path& run) {
  const int fd = ::open((run / FolderLock::kFileName).c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return false;
  const bool held = ::flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK;
  ::close(fd);  // releases the probe's shared lock, if it got one
  return held;
}

}  // namespace

std::string OverwriteHelp() {
  return "Start a new run in a folder that holds an earlier one: deletes its checkpoint.bin, "
         "config.json, results.json, data_checksums.json and best_val.bin first (other files, "
         "e.g. renders, stay). Without it such a folder is refused";
}

void RequireFreshRunFolder(const fs::path& run, bool overwrite) {
  if (overwrite || LockHeldByAnother(run)) return;
  std::vector<std::string> found;
  for (const char* name : kRunFolderFiles)
    if (Present(run / name)) found.push_back(name);
  if (found.empty()) return;
  const bool finished = Present(run / "results.json") && Present(run / "checkpoint.bin");
  const std::string what =
      finished ? "a finished run"
      : Present(run / "checkpoint.bin") ? "a run's checkpoint"
                                        : fmt::format("a run's {}", found.front());
  Fail("{}: holds {} ({}): refusing to replace it; continue it with --resume, or pass --overwrite "
       "to delete its checkpoint.bin, config.json, results.json, data_checksums.json and "
       "best_val.bin and start a new run",
       run.string(), what, fmt::join(found, ", "));
}

void RequireRunFolderNotAScene(const fs::path& run) {
  for (const char* name : {"transforms_train.json", "transforms_test.json", "transforms.json"}) {
    if (!Present(run / name)) continue;
    Fail("{}: is a scene folder (it holds {}): a run goes into a folder of its own, e.g. "
         "--out {}",
         run.string(), name, (run / "run").string());
  }
}

void RemovePreviousRun(const fs::path& run) {
  for (const char* name : kRunFolderFiles) {
    std::error_code ec;
    fs::remove(run / name, ec);  // a symlink is removed itself
    if (ec) Fail("{}: cannot delete it for --overwrite: {}", (run / name).string(), ec.message());
  }
}

CleanUpFailedStart::CleanUpFailedStart(fs::path run, bool made_folder, bool fresh_run)
    : run_(std::move(run)),
      made_folder_(made_folder),
      fresh_run_(fresh_run),
      exceptions_(std::uncaught_exceptions()) {}

CleanUpFailedStart::~CleanUpFailedStart() {
  if (std::uncaught_exceptions() == exceptions_) return;
  std::error_code ec;
  if (fresh_run_ && !Present(run_ / "checkpoint.bin")) {
    for (const char* name : kRunFolderFiles) fs::remove(run_ / name, ec);
  }
  if (!made_folder_) return;
  for (const auto& entry : fs::directory_iterator(run_, ec)) {
    if (entry.path().filename() != FolderLock::kFileName) return;
  }
  if (!ec) fs::remove_all(run_, ec);
}

}  // namespace hdr4d::method
