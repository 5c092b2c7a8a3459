// A folder of outputs built beside its final place and moved there only when complete, the way
// datagen writes scenes: a failed or killed command never leaves a half-written dataset where a
// dataset is expected, and never mixes new files into an old one. An existing non-empty folder
// is refused, not merged into (make-demo-scene over an existing dataset used to overwrite part of
// it and leave stale files).
#pragma once

#include <filesystem>

namespace hdr4d {

class StagedFolder {
 public:
  // Throws hdr4d::Error "<final_dir>: exists and is not empty ..." (or not a folder) before
  // anything is written; creates the hidden sibling ".<name>.staging-<pid>" after removing the
  // ones that processes no longer running left behind.
  explicit StagedFolder(std::filesystem::path final_dir);
  // Not committed (an exception is on its way): the staging folder and its content go.
  ~StagedFolder();
  StagedFolder(const StagedFolder&) = delete;
  StagedFolder& operator=(const StagedFolder&) = delete;

  const std::filesystem::path& path() const { return staging_; }
  // Moves the finished folder into place; refuses (keeping the staged result) if something
  // appeared at the final place meanwhile.
  void Commit();

 private:
  std::filesystem::path final_, staging_;
  bool committed_ = false;
};

}  // namespace hdr4d
