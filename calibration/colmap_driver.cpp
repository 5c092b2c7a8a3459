#include "calibration/colmap_driver.h"

#include <fmt/format.h>

#include <vector>

#include "core/util/child_process.h"
#include "core/geometry/colmap_model.h"
#include "core/files/atomic_file.h"
#include "core/util/error.h"
#include "core/util/progress.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

// A failed step's log, kept where nobody else can plant or read anything: the workspace is
// inside calibrate's staging folder, which the failure removes.
fs::path KeepLog(const fs::path& log, const std::string& step) {
  try {
    const fs::path kept = MakePrivateTempFolder("hdr4d-colmap-") / fmt::format("colmap_{}.log", step);
    fs::copy_file(log, kept);
    return kept;
  } catch (const std::exception&) {
    return log;  // no private copy possible: name the original
  }
}

void RunStep(const ColmapRunOptions& options, const std::string& step,
             std::vector<std::string> args, const fs::path& workspace) {
  const fs::path log = workspace / fmt::format("colmap_{}.log", step);
  args.insert(args.begin(), {options.binary, step});
  // Headless: no display, Qt's offscreen platform.
  const int code = RunLoggedChild(args, {"QT_QPA_PLATFORM=offscreen"}, log);
  if (code == 127)
    Fail("COLMAP not found ('{}'); install it with scripts/install-deps.sh or pass --colmap-model",
         options.binary);
  if (code != 0 && step == "mapper")
    throw ColmapNoModel(fmt::format("COLMAP mapper failed (exit {}, too few matches between the static images?): {}; "
                                    "log in {}", code, LastLogLine(log), KeepLog(log, step).string()));
  if (code != 0) {
    Fail("COLMAP {} failed (exit {}): {}; log in {}", step, code, LastLogLine(log), KeepLog(log, step).string());
  }
}

}  // namespace

fs::path RunColmap(const fs::path& image_root, const fs::path& workspace,
                   const ColmapRunOptions& options) {
  std::error_code ec;
  fs::create_directories(workspace / "sparse", ec);
  if (ec) Fail("{}: cannot create the COLMAP workspace ({})", workspace.string(), ec.message());
  fs::remove(workspace / "database.db", ec);
  Progress progress("colmap", 3, options.show_progress);
  const std::vector<std::string> db = {"--database_path", (workspace / "database.db").string()};
  auto with_db = [&](std::vector<std::string> args) {
    args.insert(args.begin(), db.begin(), db.end());
    return args;
  };
  const std::string threads = std::to_string(options.threads);
  std::vector<std::string> extract = with_db(
      {"--image_path", image_root.string(), "--ImageReader.single_camera_per_folder", "1",
       "--ImageReader.camera_model", options.camera_model, "--SiftExtraction.use_gpu", "0",
       "--SiftExtraction.num_threads", threads});
  if (options.max_image_size > 0)
    extract.insert(extract.end(), {"--SiftExtraction.max_image_size", std::to_string(options.max_image_size)});
  extract.insert(extract.end(), options.extract_args.begin(), options.extract_args.end());
  RunStep(options, "feature_extractor", extract, workspace);
  progress.Advance(1, "features");
  std::vector<std::string> match = with_db({"--SiftMatching.use_gpu", "0", "--SiftMatching.num_threads", threads});
  match.insert(match.end(), options.match_args.begin(), options.match_args.end());
  if (options.match_pairs.empty()) {
    RunStep(options, "exhaustive_matcher", match, workspace);
  } else {
    std::string list;
    for (const auto& [a, b] : options.match_pairs) list += a + " " + b + "\n";
    WriteTextFileAtomic(workspace / "match_pairs.txt", list);
    match.insert(match.end(), {"--match_list_path", (workspace / "match_pairs.txt").string(), "--match_type", "pairs"});
    RunStep(options, "matches_importer", match, workspace);
  }
  progress.Advance(1, "matches");
  std::vector<std::string> map = with_db({"--image_path", image_root.string(), "--output_path",
                                          (workspace / "sparse").string(), "--Mapper.num_threads", threads});
  map.insert(map.end(), options.map_args.begin(), options.map_args.end());
  RunStep(options, "mapper", map, workspace);
  progress.Advance(1, "mapped");
  progress.Finish();

  fs::path best;
  std::size_t best_images = 0;
  for (const auto& entry : fs::directory_iterator(workspace / "sparse")) {
    if (!entry.is_directory()) continue;
    try {
      const std::size_t n = ReadColmapModel(entry.path()).images.size();
      if (n > best_images) best_images = n, best = entry.path();
    } catch (const Error&) {
      // An unreadable partial model is no candidate.
    }
  }
  if (best.empty())
    throw ColmapNoModel(fmt::format("COLMAP could not reconstruct the static scene in {} (no model; too few "
                                    "matches between the images?)", image_root.string()));
  return best;
}

}  // namespace hdr4d
