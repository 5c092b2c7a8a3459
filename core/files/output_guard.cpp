#include "core/files/output_guard.h"

#include <sys/stat.h>

#include <algorithm>
#include <iterator>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <unordered_map>
#include <utility>

#include "core/util/error.h"
#include "core/files/dataset_folders.h"
#include "core/files/folder_lock.h"
#include "core/files/file_access.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

using FileId = std::pair<dev_t, ino_t>;

std::optional<FileId> IdOf(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return std::nullopt;
  return FileId{st.st_dev, st.st_ino};
}

// Protected paths of one kind (files or folders): by resolved path and by identity.
struct Table {
  std::unordered_map<std::string, std::string> role_by_key;
  std::map<FileId, std::set<std::string>> keys_by_id;

  void Add(const std::string& key, const std::string& role) {
    role_by_key.emplace(key, role);
    if (const auto id = IdOf(key)) keys_by_id[*id].insert(key);
  }
  // The role of the entry `key` matches, or nullptr. An identity match counts only while the
  // protected path still is that file (it may have been removed and its inode reused).
  const std::string* Match(const std::string& key, const std::optional<FileId>& id) const {
    if (const auto it = role_by_key.find(key); it != role_by_key.end()) return &it->second;
    if (!id) return nullptr;
    const auto it = keys_by_id.find(*id);
    if (it == keys_by_id.end()) return nullptr;
    for (const std::string& protected_key : it->second) {
      if (IdOf(protected_key) == id) return &role_by_key.at(protected_key);
    }
    return nullptr;
  }
};

struct Registry {
  std::mutex mutex;
  int scopes = 0;  // registrations are kept only while a scope is open
  Table files, folders;
  std::multiset<std::string> permits;
  std::unordered_map<std::string, std::string> folder_keys;  // folder as given -> its key
  std::set<std::string> named;  // command-line arguments, absolute and normalised
  std::multiset<std::string> own_runs;  // run folders this process trains (RunFolderWriter)
};

Registry& TheRegistry() {
  static Registry registry;
  return registry;
}

// Absolute, normalised, symlinks of the existing part resolved.
std::string ResolvedKey(const fs::path& path) {
  std::error_code ec;
  const fs::path absolute = fs::absolute(path, ec);
  fs::path resolved = fs::weakly_canonical(absolute, ec);
  if (ec) resolved = absolute.lexically_normal();
  std::string key = resolved.string();
  while (key.size() > 1 && key.back() == '/') key.pop_back();
  return key;
}

// The key of a file: its folder's key (cached: a dataset has thousands of files in a few
// folders) joined with its name; a file that is itself a symlink is matched through its identity.
std::string FileKey(Registry& r, const fs::path& file) {
  const std::string folder = file.parent_path().string();
  auto it = r.folder_keys.find(folder);
  if (it == r.folder_keys.end())
    it = r.folder_keys.emplace(folder, ResolvedKey(folder.empty() ? "." : folder)).first;
  return (fs::path(it->second) / file.filename()).string();
}

std::string FolderOf(const std::string& key) { return fs::path(key).parent_path().string(); }

}  // namespace

void ProtectInputFile(const fs::path& file, const std::string& role) {
  Registry& r = TheRegistry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  if (r.scopes > 0) r.files.Add(FileKey(r, file), role);
}

void ProtectInputFolder(const fs::path& folder, const std::string& role) {
  Registry& r = TheRegistry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  if (r.scopes > 0) r.folders.Add(ResolvedKey(folder), role);
}

void ProtectInput(const fs::path& path, const std::string& role) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    ProtectInputFolder(path, role);
  } else {
    ProtectInputFile(path, role);
  }
}

namespace {

// True when `key` (resolved) names one of a training run's own files (kRunFolderFiles, the lock)
// in a run folder found by looking.
bool IsFileOfARun(const std::string& key) {
  const std::string name = fs::path(key).filename().string();
  if (name != FolderLock::kFileName &&
      std::find(std::begin(kRunFolderFiles), std::end(kRunFolderFiles), name) ==
          std::end(kRunFolderFiles))
    return false;
  const fs::path folder = FolderOf(key);
  std::error_code ec;
  return fs::exists(folder / FolderLock::kFileName, ec) ||
         (fs::exists(folder / "config.json", ec) && fs::exists(folder / "checkpoint.bin", ec));
}

}  // namespace

void CheckOutput(const fs::path& path) {
  const std::string key = ResolvedKey(ResolveWriteTarget(path));
  const std::string folder = FolderOf(key);
  Registry& r = TheRegistry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  if (r.permits.count(key) > 0) return;
  if (const std::string* role = r.files.Match(key, IdOf(key))) {
    Fail("{}: refusing to write: it is {}", path.string(), *role);
  }
  if (const std::string* role = r.folders.Match(folder, IdOf(folder))) {
    Fail("{}: refusing to write into {}: it holds {}", path.string(), folder, *role);
  }
  if (r.scopes > 0 && r.own_runs.count(folder) == 0 && IsFileOfARun(key)) {
    Fail("{}: refusing to write: it is a file of training run {} (only `hdr4d train` of that run "
         "writes it)", path.string(), folder);
  }
}

void CheckOutputFile(const fs::path& path) {
  CheckOutput(path);
  const std::string folder = FolderOf(ResolvedKey(ResolveWriteTarget(path)));
  if (const std::string dataset = DatasetOfImageFolder(folder); !dataset.empty()) {
    Fail("{}: refusing to write into {}: it holds the images of dataset {} (ground truth is "
         "never overwritten)", path.string(), folder, dataset);
  }
}

void CheckOutputFolder(const fs::path& folder) {
  const std::string key = ResolvedKey(ResolveWriteTarget(folder));
  Registry& r = TheRegistry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  const std::optional<FileId> id = IdOf(key);
  if (const std::string* role = r.folders.Match(key, id)) {
    Fail("{}: refusing to write into this folder: it holds {}", folder.string(), *role);
  }
  if (const std::string* role = r.files.Match(key, id)) {
    Fail("{}: refusing to write: it is {}", folder.string(), *role);
  }
  // Also when this command read no dataset: the folder itself tells (core/files/dataset_folders.h).
  if (r.scopes > 0) {
    if (const std::string dataset = DatasetOfImageFolder(key); !dataset.empty()) {
      Fail("{}: refusing to write into this folder: it holds the images of dataset {} (ground "
           "truth is never overwritten)", folder.string(), dataset);
    }
  }
}

namespace {
std::string LexicalKey(const fs::path& path) {
  std::error_code ec;
  std::string key = fs::absolute(path, ec).lexically_normal().string();
  while (key.size() > 1 && key.back() == '/') key.pop_back();
  return key;
}
}  // namespace

void NameOnCommandLine(const std::string& argument) {
  if (argument.empty()) return;
  // "--out=x" names x; "-o" alone names nothing that exists as a file anyway.
  const std::size_t eq = argument.rfind("--", 0) == 0 ? argument.find('=') : std::string::npos;
  const std::string value = eq == std::string::npos ? argument : argument.substr(eq + 1);
  if (value.empty()) return;
  const std::string key = LexicalKey(value);
  Registry& r = TheRegistry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  if (r.scopes > 0) r.named.insert(key);
}

bool NamedOnCommandLine(const fs::path& path) {
  const std::string key = LexicalKey(path);
  Registry& r = TheRegistry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  return r.scopes == 0 || r.named.count(key) > 0;
}

bool SameFile(const fs::path& a, const fs::path& b) {
  const std::string ka = ResolvedKey(ResolveWriteTarget(a)), kb = ResolvedKey(ResolveWriteTarget(b));
  if (ka == kb) return true;
  const std::optional<FileId> ia = IdOf(ka);
  return ia && ia == IdOf(kb);
}

OutputPermit::OutputPermit(const std::vector<fs::path>& files) {
  keys_.reserve(files.size());
  for (const fs::path& f : files) keys_.push_back(ResolvedKey(ResolveWriteTarget(f)));
  Registry& r = TheRegistry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  for (const std::string& k : keys_) r.permits.insert(k);
}

OutputPermit::~OutputPermit() {
  Registry& r = TheRegistry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  for (const std::string& k : keys_) r.permits.erase(r.permits.find(k));
}

RunFolderWriter::RunFolderWriter(const fs::path& run) : key_(ResolvedKey(run)) {
  Registry& r = TheRegistry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  r.own_runs.insert(key_);
}

RunFolderWriter::~RunFolderWriter() {
  Registry& r = TheRegistry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  r.own_runs.erase(r.own_runs.find(key_));
}

InputProtectionScope::InputProtectionScope() {
  Registry& r = TheRegistry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  ++r.scopes;
}

InputProtectionScope::~InputProtectionScope() {
  Registry& r = TheRegistry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  if (--r.scopes > 0) return;
  r.files = {};
  r.folders = {};
  r.folder_keys.clear();
  r.named.clear();
}

}  // namespace hdr4d
