#include "core/files/staged_folder.h"

#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <string>

#include "core/util/error.h"
#include "core/files/file_access.h"
#include "core/files/output_guard.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

bool IsEmptyFolder(const fs::path& dir) {
  std::error_code ec;
  return fs::is_directory(dir, ec) && fs::directory_iterator(dir, ec) == fs::directory_iterator();
}

// Refuses what may not be replaced: anything but nothing or an empty folder.
void CheckFinalPlace(const fs::path& final_dir) {
  const PathProbe probe = ProbePath(final_dir);
  if (probe.kind == PathKind::kUnknown) Fail("{}: {}", final_dir.string(), probe.problem);
  if (probe.kind == PathKind::kMissing) return;
  if (probe.kind != PathKind::kFolder) Fail("{}: exists and is not a folder", final_dir.string());
  if (!IsEmptyFolder(final_dir)) {
    Fail("{}: exists and is not empty (an existing dataset is never overwritten or mixed with "
         "a new one); remove it or choose another --out",
         final_dir.string());
  }
}

// Staging folders of processes that are gone (killed) are leftovers: removed, so that they do
// not pile up. A running process's folder, or one whose owner cannot be told, is left alone.
void RemoveStaleStaging(const fs::path& parent, const std::string& prefix) {
  std::error_code ec;
  for (fs::directory_iterator it(parent, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string pid_text = name.substr(prefix.size());
    if (pid_text.empty() || pid_text.find_first_not_of("0123456789") != std::string::npos ||
        pid_text.size() > 9) {
      continue;
    }
    const pid_t pid = static_cast<pid_t>(std::stol(pid_text));
    if (::kill(pid, 0) != 0 && errno == ESRCH) {
      std::error_code ignored;
      fs::remove_all(it->path(), ignored);
    }
  }
}

}  // namespace

StagedFolder::StagedFolder(fs::path final_dir) : final_(std::move(final_dir)) {
  while (final_.has_filename() == false && final_.has_parent_path() && final_ != final_.root_path())
    final_ = final_.parent_path();  // "out/" names the folder "out"
  CheckFinalPlace(final_);
  CheckOutputFolder(final_);
  const fs::path parent = final_.has_parent_path() ? final_.parent_path() : fs::path(".");
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) Fail("{}: cannot create folder {}: {}", final_.string(), parent.string(), ec.message());
  const std::string prefix = fmt::format(".{}.staging-", final_.filename().string());
  RemoveStaleStaging(parent, prefix);
  staging_ = parent / (prefix + std::to_string(::getpid()));
  fs::remove_all(staging_, ec);  // this process's own, from an earlier attempt
  fs::create_directory(staging_, ec);
  if (ec) Fail("{}: cannot create the work folder {}: {}", final_.string(), staging_.string(),
               ec.message());
}

StagedFolder::~StagedFolder() {
  if (committed_) return;
  std::error_code ignored;
  fs::remove_all(staging_, ignored);
}

void StagedFolder::Commit() {
  CheckFinalPlace(final_);
  std::error_code ec;
  fs::rename(staging_, final_, ec);  // replaces an empty folder, never a full one
  if (ec) {
    Fail("{}: cannot move the finished folder into place from {}: {}", final_.string(),
         staging_.string(), ec.message());
  }
  committed_ = true;
}

}  // namespace hdr4d
