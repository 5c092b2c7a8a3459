// An exclusive lock on a folder for the life of one writer (hdr4d train on a run folder): a
// second writer fails at once with one line naming the holder instead of mixing its files with
// the first one's. flock(2) on FOLDER/.hdr4d-lock: the kernel releases it when the holder ends,
// kill -9 included, so a lock file left behind never blocks a later run. The file is kept (not
// unlinked on release): unlinking would let two later writers lock two different files. Taking
// the lock removes the temporary files that killed writers left in the folder
// (core/files/stale_temporaries.h): a completed resume leaves none behind.
#pragma once

#include <filesystem>
#include <string>

namespace hdr4d {

class FolderLock {
 public:
  // Throws hdr4d::Error "<folder>: in use by <holder> ..." when another process holds it;
  // `command` is what this holder says it is (e.g. "hdr4d train").
  FolderLock(const std::filesystem::path& folder, const std::string& command);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

  static constexpr const char* kFileName = ".hdr4d-lock";

 private:
  int fd_ = -1;
};

}  // namespace hdr4d
