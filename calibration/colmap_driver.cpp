#include "calibration/colmap_driver.h"

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>

#include "core/geometry/colmap_model.h"
#include "core/util/error.h"
#include "core/util/progress.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

std::string Quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string LastLine(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  return last;
}

void RunStep(const ColmapRunOptions& options, const std::string& step, const std::string& args,
             const fs::path& workspace) {
  const fs::path log = workspace / fmt::format("colmap_{}.log", step);
  // Headless: no display, Qt's offscreen platform.
  const std::string command = fmt::format("QT_QPA_PLATFORM=offscreen {} {} {} > {} 2>&1",
                                          Quote(options.binary), step, args, Quote(log.string()));
  const int status = std::system(command.c_str());
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (code == 127)
    Fail("COLMAP not found ('{}'); install it with scripts/install-deps.sh or pass --colmap-model",
         options.binary);
  if (code != 0) {
    // The workspace is inside calibrate's staging folder, which a failure removes: keep the log.
    const fs::path kept = fs::temp_directory_path() / fmt::format("hdr4d-colmap-{}-{}.log", step, getpid());
    std::error_code ec;
    fs::copy_file(log, kept, fs::copy_options::overwrite_existing, ec);
    Fail("COLMAP {} failed (exit {}{}): {}; log in {}", step, code,
         step == "mapper" ? ", too few matches between the static images?" : "", LastLine(log),
         ec ? log.string() : kept.string());
  }
}

}  // namespace

fs::path RunColmap(const fs::path& image_root, const fs::path& workspace,
                   const ColmapRunOptions& options) {
  std::error_code ec;
  fs::create_directories(workspace / "sparse", ec);
  if (ec) Fail("{}: cannot create the COLMAP workspace ({})", workspace.string(), ec.message());
  const fs::path db = workspace / "database.db";
  fs::remove(db, ec);
  Progress progress("colmap", 3, options.show_progress);
  const std::string common = fmt::format("--database_path {}", Quote(db.string()));
  RunStep(options, "feature_extractor",
          fmt::format("{} --image_path {} --ImageReader.single_camera_per_folder 1 "
                      "--ImageReader.camera_model {} --SiftExtraction.use_gpu 0 "
                      "--SiftExtraction.num_threads {}{}",
                      common, Quote(image_root.string()), options.camera_model, options.threads,
                      options.max_image_size > 0
                          ? fmt::format(" --SiftExtraction.max_image_size {}", options.max_image_size)
                          : std::string()),
          workspace);
  progress.Advance(1, "features");
  RunStep(options, "exhaustive_matcher",
          fmt::format("{} --SiftMatching.use_gpu 0 --SiftMatching.num_threads {}", common, options.threads),
          workspace);
  progress.Advance(1, "matches");
  RunStep(options, "mapper",
          fmt::format("{} --image_path {} --output_path {} --Mapper.num_threads {}", common,
                      Quote(image_root.string()), Quote((workspace / "sparse").string()), options.threads),
          workspace);
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
    Fail("COLMAP could not reconstruct the static scene in {} (no model; too few matches between "
         "the images?)", image_root.string());
  return best;
}

}  // namespace hdr4d
