#include "datagen/output_folder.h"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

#include "core/util/error.h"
#include "core/files/json_util.h"
#include "datagen/blender_render.h"
#include "core/files/sha256.h"

namespace hdr4d::datagen {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

bool IsEmptyDir(const fs::path& dir) {
  std::error_code ec;
  return fs::is_directory(dir, ec) && fs::directory_iterator(dir, ec) == fs::directory_iterator();
}

}  // namespace

bool IsDatagenOutput(const fs::path& dir) {
  const fs::path manifest = dir / kManifestFile;
  std::error_code ec;
  if (!fs::is_regular_file(manifest, ec)) return false;
  try {
    const json j = ReadJsonFile(manifest);
    return j.is_object() && j.contains("generator") && j["generator"] == kGenerator;
  } catch (const Error&) {
    return false;
  }
}

fs::path PrepareStaging(const fs::path& final_dir, const std::string& scene) {
  std::error_code ec;
  if (fs::exists(final_dir, ec) &&
      !(fs::is_directory(final_dir, ec) && (IsEmptyDir(final_dir) || IsDatagenOutput(final_dir)))) {
    Fail(
        "{}: exists and is not the output of a previous `hdr4d datagen` run (no manifest.json "
        "naming it); choose another --out or remove it",
        final_dir.string());
  }
  const fs::path staging = final_dir.string() + ".partial";
  if (fs::exists(staging, ec)) {
    if (!fs::is_directory(staging, ec) ||
        !(IsEmptyDir(staging) || fs::exists(staging / kPlanFile, ec))) {
      Fail("{}: exists and is not a datagen work folder; remove it to render scene '{}'",
           staging.string(), scene);
    }
    fs::remove_all(staging, ec);
    if (ec) Fail("{}: cannot remove the previous work folder: {}", staging.string(), ec.message());
  }
  fs::create_directories(staging, ec);
  if (ec || !fs::is_directory(staging)) {
    Fail("{}: cannot create the output folder: {}", staging.string(),
         ec ? ec.message() : "not a directory");
  }
  return staging;
}

json Checksums(const fs::path& root) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (!entry.is_regular_file()) continue;
    const fs::path relative = fs::relative(entry.path(), root);
    // The log holds timings and the manifest holds the checksums: neither is reproducible.
    if (relative == kManifestFile || relative == kLogFile) continue;
    files.push_back(relative);
  }
  std::sort(files.begin(), files.end());
  json out = json::object();
  for (const fs::path& f : files) out[f.generic_string()] = Sha256File(root / f);
  return out;
}

void MoveIntoPlace(const fs::path& staging, const fs::path& final_dir) {
  std::error_code ec;
  if (fs::exists(final_dir, ec)) {
    // Checked before rendering: empty, or a previous datagen output of this scene.
    fs::remove_all(final_dir, ec);
    if (ec) Fail("{}: cannot replace the previous output: {}", final_dir.string(), ec.message());
  }
  fs::rename(staging, final_dir, ec);
  if (ec) {
    Fail("{}: cannot move the finished scene into place from {}: {}", final_dir.string(),
         staging.string(), ec.message());
  }
}

double FinishOutput(nlohmann::json manifest,
                    double blender_seconds,
                    int renders,
                    std::chrono::steady_clock::time_point start,
                    const std::filesystem::path& staging,
                    const std::filesystem::path& final_dir) {
  const double total_seconds = SecondsSince(start);
  manifest["timing"] = {{"blender_seconds", blender_seconds},
                        {"seconds_per_render", blender_seconds / renders},
                        {"total_seconds", total_seconds}};
  manifest["files"] = Checksums(staging);
  WriteJsonFile(staging / kManifestFile, manifest);
  MoveIntoPlace(staging, final_dir);
  return total_seconds;
}

}  // namespace hdr4d::datagen
