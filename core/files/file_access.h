// Why an input cannot be read, said the same way by every reader: "not found" only when nothing
// is there, "permission denied" when something is there (or may be) that this user may not read,
// "is a folder" / "is not a folder" when the kind is wrong. std::filesystem::exists() reports a
// folder that cannot be entered as "does not exist", which is how a permission problem used to
// be reported as a missing file.
#pragma once

#include <filesystem>
#include <string>

namespace hdr4d {

enum class PathKind { kMissing, kFile, kFolder, kOther, kUnknown };

struct PathProbe {
  PathKind kind = PathKind::kUnknown;  // kUnknown: stat failed for another reason than absence
  bool readable = false;               // files: may be read; folders: may be listed and entered
  std::string problem;                 // for kUnknown and unreadable paths: what stat/access said
};

// One stat() and one access() (symlinks followed).
PathProbe ProbePath(const std::filesystem::path& path);

// What a path that is not a regular file or folder is: "a character device", "a FIFO", ...;
// "" for regular files, folders and paths that cannot be stat()ed.
std::string SpecialFileKind(const std::filesystem::path& path);

// "" when `path` is a readable regular file; else the problem, e.g. "file not found",
// "permission denied", "is a folder, expected a file", "is a character device, not a regular
// file". Devices, FIFOs and sockets are refused by name before anything opens them: reading
// /dev/zero never ends, and opening a FIFO blocks until a writer comes.
std::string InputFileProblem(const std::filesystem::path& path);
// "" when `path` is a folder that can be listed and entered; else the problem.
std::string InputFolderProblem(const std::filesystem::path& path);

// Throw hdr4d::Error "<path>: <problem>" when the problem above is not empty.
void RequireInputFile(const std::filesystem::path& path);
void RequireInputFolder(const std::filesystem::path& path);

// True when something is at `path`; throws "<path>: permission denied" when that cannot be told
// (a folder on the way may not be entered), instead of answering "no" as fs::exists does.
bool PathExists(const std::filesystem::path& path);

// The end of `path`'s chain of symlinks, also when it dangles (its target is where a new file
// would be created). Throws "<path>: too many levels of symbolic links".
std::filesystem::path FollowSymlinks(const std::filesystem::path& path);

// The file a write to `path` ends in: the resolved path when something exists there (realpath,
// which also understands /proc's fd links), else the end of its symlink chain.
std::filesystem::path ResolveWriteTarget(const std::filesystem::path& path);

}  // namespace hdr4d
