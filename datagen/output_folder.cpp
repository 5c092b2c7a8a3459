#include "datagen/output_folder.h"

#include <fmt/format.h>

#include <algorithm>
#include <optional>
#include <set>
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

// The manifest of a previous datagen run in `dir`, or nothing.
std::optional<json> DatagenManifest(const fs::path& dir) {
  const fs::path manifest = dir / kManifestFile;
  std::error_code ec;
  if (!fs::is_regular_file(manifest, ec)) return std::nullopt;
  try {
    json j = ReadJsonFile(manifest);
    if (j.is_object() && j.contains("generator") && j["generator"] == kGenerator) return j;
  } catch (const Error&) {
  }
  return std::nullopt;
}

// What a previous run wrote, relative to its folder: the files its manifest lists, the manifest
// and the log; `dirs` gets every folder above one of them.
std::set<std::string> OwnFiles(const json& manifest, std::set<std::string>* dirs) {
  std::set<std::string> files = {kManifestFile, kLogFile};
  if (manifest.contains("files") && manifest["files"].is_object()) {
    for (const auto& [name, sha] : manifest["files"].items()) files.insert(name);
  }
  for (const std::string& f : files) {
    for (fs::path p = fs::path(f).parent_path(); !p.empty(); p = p.parent_path())
      dirs->insert(p.generic_string());
  }
  return files;
}

// True when `file`, listed in the manifest as `relative`, no longer has the SHA-256 the manifest
// gives it: someone edited or replaced it, so it is not datagen's to delete any more.
bool ChangedSinceWritten(const fs::path& file, const std::string& relative, const json& manifest) {
  const auto files = manifest.find("files");
  // The manifest and the log carry no checksum.
  if (files == manifest.end() || !files->is_object() || !files->contains(relative)) return false;
  const json& sha = files->at(relative);
  return !sha.is_string() || Sha256File(file) != sha.get<std::string>();
}

// The entries of `dir` that the run its manifest describes did not write (sorted): files it
// does not list or that changed since (their SHA-256 differs), folders above none of them that
// are not empty, links and anything else (datagen writes none).
// The own files and folders found go to `own_files` and `own_dirs` when given.
std::vector<std::string> ForeignEntries(const fs::path& dir, const json& manifest,
                                        std::vector<fs::path>* own_files = nullptr,
                                        std::vector<fs::path>* own_dirs = nullptr) {
  std::set<std::string> dirs;
  const std::set<std::string> files = OwnFiles(manifest, &dirs);
  std::vector<std::string> foreign;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != end(it);
       it.increment(ec)) {
    const std::string relative = it->path().lexically_relative(dir).generic_string();
    const fs::file_status status = it->symlink_status(ec);
    if (ec) break;
    if (fs::is_regular_file(status) && files.count(relative)) {
      if (ChangedSinceWritten(it->path(), relative, manifest)) {
        foreign.push_back(relative + " (changed since datagen wrote it)");
      } else if (own_files) {
        own_files->push_back(it->path());
      }
    } else if (fs::is_directory(status) && (dirs.count(relative) || IsEmptyDir(it->path()))) {
      // An empty folder holds nothing to lose (a run may leave one, the manifest lists files).
      if (own_dirs) own_dirs->push_back(it->path());
    } else {
      foreign.push_back(relative + (fs::is_directory(status) ? "/" : ""));
      if (fs::is_directory(status)) it.disable_recursion_pending();
    }
  }
  if (ec) Fail("{}: cannot list the previous output: {}", dir.string(), ec.message());
  std::sort(foreign.begin(), foreign.end());
  return foreign;
}

// Refuses to replace `final_dir` when it holds anything its previous run did not write.
void CheckOnlyOwnFiles(const fs::path& final_dir, const json& manifest) {
  const std::vector<std::string> foreign = ForeignEntries(final_dir, manifest);
  if (foreign.empty()) return;
  Fail(
      "{}: holds {}{}, which the previous `hdr4d datagen` run did not write (not in its "
      "manifest.json, or not with the SHA-256 it lists); a rerun replaces only datagen's own "
      "files: move it out of the folder, or choose another --out",
      final_dir.string(), foreign.front(),
      foreign.size() > 1 ? fmt::format(" and {} more entries", foreign.size() - 1) : "");
}

// Deletes the files and folders of the previous run in `final_dir` and the folder itself,
// after checking again that nothing else is there (the render takes minutes).
void RemoveOwnOutput(const fs::path& final_dir, const json& manifest) {
  CheckOnlyOwnFiles(final_dir, manifest);
  std::vector<fs::path> files, dirs;
  ForeignEntries(final_dir, manifest, &files, &dirs);
  std::error_code ec;
  for (const fs::path& f : files) {
    if (!fs::remove(f, ec) && ec)
      Fail("{}: cannot remove the previous output's file: {}", f.string(), ec.message());
  }
  // Deepest first; fs::remove leaves a folder that is not empty (something new appeared).
  std::sort(dirs.rbegin(), dirs.rend());
  dirs.push_back(final_dir);
  for (const fs::path& d : dirs) {
    if (!fs::remove(d, ec) && ec)
      Fail("{}: cannot replace the previous output: {} (anything new in it is kept)", d.string(),
           ec.message());
  }
}

}  // namespace

bool IsDatagenOutput(const fs::path& dir) { return DatagenManifest(dir).has_value(); }

fs::path PrepareStaging(const fs::path& final_dir, const std::string& scene) {
  std::error_code ec;
  if (fs::exists(final_dir, ec) &&
      !(fs::is_directory(final_dir, ec) && (IsEmptyDir(final_dir) || IsDatagenOutput(final_dir)))) {
    Fail(
        "{}: exists and is not the output of a previous `hdr4d datagen` run (no manifest.json "
        "naming it); choose another --out or remove it",
        final_dir.string());
  }
  const std::optional<json> manifest = DatagenManifest(final_dir);
  if (manifest && !fs::is_symlink(final_dir, ec)) CheckOnlyOwnFiles(final_dir, *manifest);
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
  if (fs::exists(final_dir, ec) || fs::is_symlink(final_dir, ec)) {
    // Checked before rendering too: empty, or a previous datagen output of this scene. A link
    // goes, not what it points to.
    const std::optional<json> manifest = DatagenManifest(final_dir);
    if (fs::is_symlink(final_dir, ec) || IsEmptyDir(final_dir)) {
      fs::remove(final_dir, ec);
    } else if (!manifest) {
      Fail("{}: is no longer the output of a previous `hdr4d datagen` run; the finished scene "
           "stays in {}", final_dir.string(), staging.string());
    } else {
      RemoveOwnOutput(final_dir, *manifest);
    }
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
