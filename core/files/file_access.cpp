#include "core/files/file_access.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "core/util/error.h"

namespace hdr4d {
namespace fs = std::filesystem;

PathProbe ProbePath(const fs::path& path) {
  PathProbe probe;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int err = errno;
    if (err == ENOENT || err == ENOTDIR) {
      probe.kind = PathKind::kMissing;
    } else if (err == EACCES) {
      probe.problem = "permission denied (a folder on the way cannot be entered)";
    } else {
      probe.problem = std::strerror(err);
    }
    return probe;
  }
  probe.kind = S_ISREG(st.st_mode)   ? PathKind::kFile
               : S_ISDIR(st.st_mode) ? PathKind::kFolder
                                     : PathKind::kOther;
  const int mode = probe.kind == PathKind::kFolder ? (R_OK | X_OK) : R_OK;
  probe.readable = ::access(path.c_str(), mode) == 0;
  if (!probe.readable) probe.problem = errno == EACCES ? "permission denied" : std::strerror(errno);
  return probe;
}

std::string SpecialFileKind(const fs::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return "";
  if (S_ISCHR(st.st_mode)) return "a character device";
  if (S_ISBLK(st.st_mode)) return "a block device";
  if (S_ISFIFO(st.st_mode)) return "a FIFO (named pipe)";
  if (S_ISSOCK(st.st_mode)) return "a socket";
  if (S_ISREG(st.st_mode) || S_ISDIR(st.st_mode)) return "";
  return "a special file";
}

std::string InputFileProblem(const fs::path& path) {
  const PathProbe p = ProbePath(path);
  switch (p.kind) {
    case PathKind::kMissing:
      return "file not found";
    case PathKind::kUnknown:
      return p.problem;
    case PathKind::kFolder:
      return "is a folder, expected a file";
    case PathKind::kOther: {
      const std::string kind = SpecialFileKind(path);
      return "is " + (kind.empty() ? std::string("a special file") : kind) +
             ", not a regular file";
    }
    case PathKind::kFile:
      return p.readable ? "" : p.problem;
  }
  return "";
}

std::string InputFolderProblem(const fs::path& path) {
  const PathProbe p = ProbePath(path);
  switch (p.kind) {
    case PathKind::kMissing:
      return "folder not found";
    case PathKind::kUnknown:
      return p.problem;
    case PathKind::kFile:
    case PathKind::kOther:
      return "is not a folder";
    case PathKind::kFolder:
      return p.readable ? "" : p.problem;
  }
  return "";
}

void RequireInputFile(const fs::path& path) {
  if (std::string problem = InputFileProblem(path); !problem.empty())
    Fail("{}: {}", path.string(), problem);
}

void RequireInputFolder(const fs::path& path) {
  if (std::string problem = InputFolderProblem(path); !problem.empty())
    Fail("{}: {}", path.string(), problem);
}

bool PathExists(const fs::path& path) {
  const PathProbe p = ProbePath(path);
  if (p.kind == PathKind::kUnknown) Fail("{}: {}", path.string(), p.problem);
  return p.kind != PathKind::kMissing;
}

fs::path FollowSymlinks(const fs::path& path) {
  constexpr int kMaxHops = 40;  // as the kernel's ELOOP limit
  fs::path p = path;
  for (int hops = 0;; ++hops) {
    std::error_code ec;
    if (!fs::is_symlink(fs::symlink_status(p, ec))) return p;
    if (hops == kMaxHops) Fail("{}: too many levels of symbolic links", path.string());
    const fs::path link = fs::read_symlink(p, ec);
    if (ec) Fail("{}: cannot read the symbolic link {}: {}", path.string(), p.string(), ec.message());
    p = link.is_absolute() ? link : p.parent_path() / link;
  }
}

fs::path ResolveWriteTarget(const fs::path& path) {
  std::error_code ec;
  fs::path resolved = fs::canonical(path, ec);
  return ec ? FollowSymlinks(path) : resolved;
}

}  // namespace hdr4d
