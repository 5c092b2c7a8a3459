#include "core/files/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <memory>

#include "core/util/error.h"
#include "core/files/file_access.h"
#include "core/files/output_guard.h"
#include "core/files/temporary_cleanup.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

// Hidden and without an image or JSON extension: nothing that lists a folder takes a temporary
// file left by a killed process for an output.
fs::path TemporaryName(const fs::path& folder, const fs::path& target) {
  static std::atomic<unsigned> counter{0};
  return folder / fmt::format(".{}.tmp-{}-{}", target.filename().string(), ::getpid(), counter++);
}

// Fills a temporary file, removing it when `fill` fails.
void FillTemporary(const fs::path& tmp,
                   const std::function<void(const fs::path&)>& fill) {
  try {
    fill(tmp);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

// Copies a finished file into a special file (a device, a FIFO) that must not be replaced.
void CopyInto(const fs::path& from, const fs::path& to) {
  const int in = ::open(from.c_str(), O_RDONLY | O_CLOEXEC);
  if (in < 0) Fail("{}: cannot reopen the written data: {}", to.string(), std::strerror(errno));
  const int out = ::open(to.c_str(), O_WRONLY | O_CLOEXEC);
  if (out < 0) {
    const int err = errno;
    ::close(in);
    Fail("{}: cannot open for writing: {}", to.string(), std::strerror(err));
  }
  char buffer[1 << 16];
  std::string why;
  for (;;) {
    const ssize_t n = ::read(in, buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) why = std::strerror(errno);
    if (n <= 0) break;
    for (ssize_t done = 0; done < n && why.empty();) {
      const ssize_t w = ::write(out, buffer + done, static_cast<std::size_t>(n - done));
      if (w < 0 && errno == EINTR) continue;
      if (w < 0) why = std::strerror(errno);
      if (w > 0) done += w;
    }
    if (!why.empty()) break;
  }
  ::close(in);
  if (::close(out) != 0 && why.empty()) why = std::strerror(errno);
  if (!why.empty()) Fail("{}: write failed: {}", to.string(), why);
}

// A write in two halves: Prepare checks the guard and fills the temporary file; Publish moves it
// into place (or copies it into a special file).
struct PreparedWrite {
  fs::path path, tmp, target;  // target empty: `path` is a special file, written through
  bool existed = false;
  std::shared_ptr<TrackedTemporary> tracked;  // unlinked by a stop signal until published
};

// A symlink or special file found at `path` that the user did not name on the command line
// (issue 51, case 11: a planted `checkpoint.bin -> victim` inside --out was written through).
bool ReplaceRatherThanFollow(const fs::path& path) {
  struct stat lst {};
  if (::lstat(path.c_str(), &lst) != 0) return false;
  if (S_ISREG(lst.st_mode) || S_ISDIR(lst.st_mode)) return false;
  return !NamedOnCommandLine(path);
}

PreparedWrite Prepare(const fs::path& path, const std::function<void(const fs::path&)>& fill) {
  CheckOutput(path);
  struct stat st {};
  PreparedWrite w{path, {}, {}, ::stat(path.c_str(), &st) == 0};
  if (w.existed && S_ISDIR(st.st_mode)) Fail("{}: is a folder, expected a file", path.string());
  std::error_code ec;
  if (ReplaceRatherThanFollow(path)) {
    // A symlink or special file the user did not name: the new file takes its place.
    w.target = path;
    w.existed = false;  // the link's or node's mode is not the new file's
    const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
    w.tmp = TemporaryName(folder, path);
  } else if (w.existed && !S_ISREG(st.st_mode)) {
    // Written through later: the data is made in the temporary folder first, so a failing
    // writer sends nothing half-made into the device or pipe.
    w.tmp = TemporaryName(fs::temp_directory_path(ec), path);
  } else {
    // A symlink keeps pointing where it did: its target is replaced.
    w.target = ResolveWriteTarget(path);
    const fs::path folder = w.target.has_parent_path() ? w.target.parent_path() : fs::path(".");
    fs::create_directories(folder, ec);
    if (ec) Fail("{}: cannot create folder {}: {}", path.string(), folder.string(), ec.message());
    w.tmp = TemporaryName(folder, w.target);
  }
  w.tracked = std::make_shared<TrackedTemporary>(w.tmp);
  FillTemporary(w.tmp, fill);
  return w;
}

void Publish(const PreparedWrite& w) {
  std::error_code ec;
  if (w.target.empty()) {
    try {
      CopyInto(w.tmp, w.path);
    } catch (...) {
      fs::remove(w.tmp, ec);
      throw;
    }
    fs::remove(w.tmp, ec);
    return;
  }
  if (w.existed) fs::permissions(w.tmp, fs::status(w.target, ec).permissions(), ec);  // its mode
  fs::rename(w.tmp, w.target, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(w.tmp, ignored);
    Fail("{}: cannot move the written file into place: {}", w.path.string(), ec.message());
  }
}

}  // namespace

void WriteFileAtomicAt(const fs::path& path, const std::function<void(const fs::path&)>& fill) {
  Publish(Prepare(path, fill));
}

void WriteFileAtomic(const fs::path& path, const std::function<void(std::ostream&)>& write) {
  WriteFileAtomicAt(path, [&](const fs::path& tmp) {
    std::ofstream file(tmp, std::ios::binary | std::ios::trunc);
    if (!file) Fail("{}: cannot open for writing: {}", path.string(), std::strerror(errno));
    write(file);
    file.flush();
    if (!file) Fail("{}: write failed (disk full?)", path.string());
    file.close();
    if (!file) Fail("{}: write failed (disk full?)", path.string());
  });
}

void WriteTextFileAtomic(const fs::path& path, const std::string& text) {
  WriteFileAtomic(path, [&](std::ostream& out) { out << text; });
}

FileBatch::~FileBatch() {
  if (committed_) return;
  std::error_code ignored;
  for (const Pending& p : pending_) fs::remove(p.tmp, ignored);
}

void FileBatch::Write(const fs::path& path, const std::function<void(const fs::path&)>& fill) {
  const PreparedWrite w = Prepare(path, fill);
  const std::lock_guard<std::mutex> lock(mutex_);
  pending_.push_back({w.path, w.tmp, w.target, w.existed, w.tracked});
}

void FileBatch::Commit() {
  const std::lock_guard<std::mutex> lock(mutex_);
  for (std::size_t i = 0; i < pending_.size(); ++i) {
    const Pending& p = pending_[i];
    try {
      Publish({p.path, p.tmp, p.target, p.existed, p.tracked});
    } catch (...) {
      // The ones not published yet stay temporary and go with the destructor.
      pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(i) + 1);
      throw;
    }
  }
  committed_ = true;
}

}  // namespace hdr4d
