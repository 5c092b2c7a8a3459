#include "core/files/made_folders.h"

namespace hdr4d {
namespace fs = std::filesystem;

fs::path FirstMissingFolder(const fs::path& out) {
  std::error_code ec;
  fs::path missing;
  for (fs::path p = out; !fs::exists(p, ec); p = p.parent_path()) {
    missing = p;
    if (p == p.parent_path()) break;
  }
  return missing;
}

void RemoveIfEmptyTree(const fs::path& folder) {
  std::error_code ec;
  if (folder.empty() || !fs::is_directory(fs::symlink_status(folder, ec))) return;
  for (auto it = fs::recursive_directory_iterator(folder, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec))
    if (!it->is_directory(ec) || it->is_symlink(ec)) return;
  fs::remove_all(folder, ec);
}

}  // namespace hdr4d
