// What `hdr4d train --out RUN` may find in RUN and what it leaves there (issue 51 §3, §18, §20):
// a new run never silently replaces an earlier one, a failed start leaves no half run, and a
// finished run resumed again is left as it is.
#pragma once

#include <filesystem>
#include <string>

namespace hdr4d::method {

// The record of the run's data (core/dataset/dataset_checksum.h), compared on --resume.
inline constexpr const char* kDataRecordName = "data_checksums.json";

// For a new run (no --resume): throws hdr4d::Error when RUN holds a run's files (a finished run,
// a checkpoint, a configuration) and `overwrite` is false, naming what is there, --resume and
// --overwrite. Checked before the scene is read (unless another writer holds RUN's lock: taking
// the lock then says so) and again once the lock is held.
void RequireFreshRunFolder(const std::filesystem::path& run, bool overwrite);

// Throws hdr4d::Error when RUN is a scene folder (it holds transforms_*.json or transforms.json,
// --data's or another's): a run written there mixes its files and lock with the scene's, and a
// later `--overwrite` deletes files among them. Checked first, for new runs and resumes alike.
void RequireRunFolderNotAScene(const std::filesystem::path& run);

// --overwrite, with the run's lock held: removes a run's files (kRunFolderFiles,
// core/files/output_guard.h) from RUN (a symlink itself, never its target). Other files (renders,
// exports, notes) stay.
void RemovePreviousRun(const std::filesystem::path& run);

// The help of --overwrite, naming what it deletes.
std::string OverwriteHelp();

// Removes what a new run wrote when it fails before its first checkpoint (a full disk, a bad
// image found late, an exception of any kind): the run's files (kRunFolderFiles), and RUN itself
// when this run made it and nothing but the lock is left; a run with a checkpoint is kept.
class CleanUpFailedStart {
 public:
  CleanUpFailedStart(std::filesystem::path run, bool made_folder, bool fresh_run);
  ~CleanUpFailedStart();
  CleanUpFailedStart(const CleanUpFailedStart&) = delete;
  CleanUpFailedStart& operator=(const CleanUpFailedStart&) = delete;

 private:
  std::filesystem::path run_;
  bool made_folder_;
  bool fresh_run_;
  int exceptions_;
};

}  // namespace hdr4d::method
