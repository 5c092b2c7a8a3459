// `hdr4d bench submit`: scores a folder of renders made by any method (for example the official
// CUDA code on a GPU) against a scene's test split with the same evaluation as the harness, and
// stores it under its own method name, so external methods sit in the same tables. The renders
// are named like the ground truth (what `hdr4d render` writes): LDR as each test frame's
// file_path (.png), HDR as its exr_file_path (.exr). Either kind may be absent; a kind that is
// there must be complete, and no other image may be in the folder.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "benchmark/run_record.h"

namespace hdr4d::bench {

struct SubmitOptions {
  std::filesystem::path store;
  std::string method;
  std::string scene;  // a dataset folder, or a scene name of `suite`
  std::string suite;  // optional: the suite whose tables the submission joins
  std::filesystem::path renders;
  std::filesystem::path meta;  // optional JSON: train_seconds, render_fps, gaussians, ...
  std::string supervision = "ldr";
  std::int64_t seed = 0;
  bool replace = false;  // replace an earlier submission under the same label
  std::filesystem::path cache_dir;
};

// The meta file's keys: train_seconds, render_fps, gaussians, peak_rss_mb, iterations,
// code_version (of the external code), machine (object, or text kept as {"description": text}),
// notes. Anything else is an error naming the file and the key.
nlohmann::json ReadSubmissionMeta(const std::filesystem::path& path);

// Throws hdr4d::Error (naming the file) for missing or extra frames, wrong sizes, NaN/Inf
// pixels, a bad meta file, or a label held by another run; the store is untouched then.
RunRecord Submit(const SubmitOptions& options);

}  // namespace hdr4d::bench
