// Every file hdr4d writes goes through WriteFileAtomic, so every writer gets the same rules:
//  - the output guard is asked first (core/files/output_guard.h): never over an input, never into a
//    dataset's image folders;
//  - a regular file (or a new one) is written to a hidden temporary file beside it,
//    ".<name>.tmp-<pid>-<n>", renamed over it only when complete, so a failed or killed write
//    leaves the previous file and nothing a reader takes for an image or a JSON file;
//  - a symlink the user named on the command line is written through (its target gets the new
//    content, the link stays);
//  - a special file the user named (/dev/null, /dev/stdout, a FIFO) is written directly: renaming
//    over it would replace the device node with a regular file;
//  - a symlink or special file the user did not name (one found inside --out, e.g. a planted
//    `checkpoint.bin -> victim`) is replaced by the new file: its target is never touched
//    (NamedOnCommandLine in core/files/output_guard.h).
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <ostream>
#include <string>
#include <vector>

namespace hdr4d {

class TrackedTemporary;  // core/files/temporary_cleanup.h

// Creates the parent folders, lets `write` fill the temporary file (binary mode), then moves it
// into place. On any failure the temporary file is removed, `path` keeps what it had, and
// hdr4d::Error names `path`.
void WriteFileAtomic(const std::filesystem::path& path,
                     const std::function<void(std::ostream&)>& write);

// The same for writers that need a file name (the image formats): `fill(tmp)` writes the complete file
// at `tmp` (whose name ends in ".tmp-<pid>-<n>", not in the target's extension).
void WriteFileAtomicAt(const std::filesystem::path& path,
                       const std::function<void(const std::filesystem::path& tmp)>& fill);

void WriteTextFileAtomic(const std::filesystem::path& path, const std::string& text);

// Outputs that belong together (the LDR images of a dataset, the renders of a split, the frames
// of a video): each is written to its temporary file as it is made, with the rules above, and
// all are moved into place only by Commit(), once every one succeeded. A failure or a kill
// before that leaves the previous files as they were: never a mix of old and new outputs.
class FileBatch {
 public:
  FileBatch() = default;
  ~FileBatch();  // not committed: the temporary files are removed
  FileBatch(const FileBatch&) = delete;
  FileBatch& operator=(const FileBatch&) = delete;

  // As WriteFileAtomicAt, except that the move into place waits for Commit(). Thread-safe.
  void Write(const std::filesystem::path& path,
             const std::function<void(const std::filesystem::path& tmp)>& fill);
  void Commit();

 private:
  struct Pending {
    std::filesystem::path path, tmp, target;  // target empty: a special file, copied into
    bool existed = false;
    std::shared_ptr<TrackedTemporary> tracked;  // core/files/temporary_cleanup.h
  };
  std::mutex mutex_;
  std::vector<Pending> pending_;
  bool committed_ = false;
};

}  // namespace hdr4d
