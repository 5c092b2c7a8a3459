// Folders a command makes for its output, and taking them away again when it fails: no empty
// output folder is left behind (issue 51 §20 for calibrate; render since stop 94).
#pragma once

#include <filesystem>

namespace hdr4d {

// The outermost folder of `out` that does not exist yet (empty when `out` exists): what a command
// writing into `out` creates, and so what its failure takes away again.
std::filesystem::path FirstMissingFolder(const std::filesystem::path& out);

// Removes `folder` when it holds nothing but empty folders (never a file someone put there); an
// empty path or a missing folder is left alone.
void RemoveIfEmptyTree(const std::filesystem::path& folder);

}  // namespace hdr4d
