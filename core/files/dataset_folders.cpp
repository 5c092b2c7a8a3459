#include "core/files/dataset_folders.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <system_error>

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

constexpr int kLevels = 3;  // images/, hdr/, images/cam0/ (the layout calibrate writes)
constexpr const char* kTransforms[] = {"transforms_train.json", "transforms_test.json",
                                       "transforms_val.json", "transforms.json"};

// True when a frame of `json_file` has an image inside `rel` (a folder relative to the dataset).
bool FramesInside(const fs::path& json_file, const fs::path& rel) {
  std::error_code ec;
  if (!fs::is_regular_file(json_file, ec)) return false;
  std::ifstream in(json_file, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  const nlohmann::json doc = nlohmann::json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
  if (!doc.is_object() || !doc.contains("frames") || !doc["frames"].is_array()) return false;
  const std::string prefix = rel.lexically_normal().string() + "/";
  for (const nlohmann::json& frame : doc["frames"]) {
    if (!frame.is_object()) continue;
    for (const char* key : {"file_path", "exr_file_path"}) {
      if (!frame.contains(key) || !frame[key].is_string()) continue;
      std::string p = fs::path(frame[key].get<std::string>()).lexically_normal().string();
      if (p.rfind("./", 0) == 0) p = p.substr(2);
      if (p.rfind(prefix, 0) == 0) return true;
    }
  }
  return false;
}

}  // namespace

std::string DatasetOfImageFolder(const fs::path& folder) {
  std::error_code ec;
  fs::path resolved = fs::weakly_canonical(fs::absolute(folder, ec), ec);
  if (ec) return "";
  fs::path rel;
  fs::path dataset = resolved;
  for (int level = 0; level < kLevels && dataset.has_relative_path(); ++level) {
    rel = rel.empty() ? dataset.filename() : dataset.filename() / rel;
    dataset = dataset.parent_path();
    for (const char* name : kTransforms) {
      if (FramesInside(dataset / name, rel)) return dataset.string();
    }
  }
  return "";
}

}  // namespace hdr4d
