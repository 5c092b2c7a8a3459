// Temporary files of writers that died: core/files/atomic_file.cpp writes every file to a hidden
// ".<name>.tmp-<pid>-<n>" beside it, and a writer killed before the rename leaves it behind
// (+52 MB of checkpoint temporaries after ten kills, issue 51 case 19).
#pragma once

#include <filesystem>

namespace hdr4d {

// Removes the temporaries directly inside `folder` whose writer is no longer running (its pid
// does not exist); those of live processes, this one included, are kept. Returns how many went.
// Best effort: a file that cannot be removed is left.
int RemoveStaleTemporaries(const std::filesystem::path& folder);

}  // namespace hdr4d
