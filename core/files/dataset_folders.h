// Whether a folder holds a dataset's images, told from the folder alone: a command that reads no
// dataset (bench table, bench pareto, bench report) cannot have registered one with the output
// guard, yet `bench table --out SCENE/images` wrote among the ground truth (issue 51, case 10).
#pragma once

#include <filesystem>
#include <string>

namespace hdr4d {

// "" unless `folder` (or a folder inside it) is where a dataset's frames are: a folder up to
// three levels above it holds transforms_{train,test,val}.json or transforms.json, and one of
// their frames' "file_path" / "exr_file_path" lies inside `folder`. Then the dataset's folder.
// Unreadable or malformed JSON counts as no dataset (the check is for writers, not a validator).
std::string DatasetOfImageFolder(const std::filesystem::path& folder);

}  // namespace hdr4d
