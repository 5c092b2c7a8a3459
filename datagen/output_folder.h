// The output folder of one datagen scene (a dataset or a capture): built in OUT/<scene>.partial
// and moved into place only when complete, so a failed run keeps the previous output; a folder
// that holds anything but a previous datagen run is never replaced. A rerun deletes only what
// the previous run wrote (the files its manifest lists, still with the SHA-256 it lists, the
// manifest and blender.log): a scene folder that holds anything else (notes, a training run, an
// edited image) is refused, naming the first entry.
#pragma once

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace hdr4d::datagen {

inline constexpr const char* kGenerator = "hdr4d datagen";  // manifest.json's "generator"
inline constexpr const char* kManifestFile = "manifest.json";

// True when `dir` holds a previous datagen run (its manifest names this generator).
bool IsDatagenOutput(const std::filesystem::path& dir);

// Checks that `final_dir` may be written (absent, empty or a previous datagen run holding only
// its own files) and returns a fresh staging folder next to it. Throws hdr4d::Error naming the
// folder, or the first entry the previous run did not write, otherwise.
std::filesystem::path PrepareStaging(const std::filesystem::path& final_dir,
                                     const std::string& scene);

// SHA-256 of every file under `root` by relative path, except the manifest and Blender's log
// (neither is reproducible).
nlohmann::json Checksums(const std::filesystem::path& root);

// Replaces `final_dir` (checked by PrepareStaging) with the finished `staging` folder, deleting
// only the previous run's own files; anything else found there now is an error and `staging`
// stays.
void MoveIntoPlace(const std::filesystem::path& staging, const std::filesystem::path& final_dir);

inline double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Finishes a scene's output: the timing (Blender's seconds over `renders`, the total since
// `start`) and the checksum of every file into `manifest`, written into `staging`, which then
// replaces `final_dir`. Returns the total seconds (taken before the checksums).
double FinishOutput(nlohmann::json manifest,
                    double blender_seconds,
                    int renders,
                    std::chrono::steady_clock::time_point start,
                    const std::filesystem::path& staging,
                    const std::filesystem::path& final_dir);

}  // namespace hdr4d::datagen
