#include "core/dataset/val_split.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <set>
#include <vector>

#include "core/dataset/dataset.h"
#include "core/files/json_util.h"
#include "core/files/staged_folder.h"
#include "core/util/error.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

// Which training frames (by their index in transforms_train.json) go to val, and in words.
std::set<int> ChooseValFrames(const Dataset& scene,
                              const ValSplitOptions& options,
                              const fs::path& train_json,
                              std::string* what) {
  std::set<int> chosen;
  if (options.camera_id >= 0) {
    std::set<int> cameras;
    for (const Frame& f : scene.train) {
      cameras.insert(f.camera_id);
      if (f.camera_id == options.camera_id) chosen.insert(f.index);
    }
    if (chosen.empty()) {
      cameras.erase(-1);
      Fail("{}: no training frame has camera_id {} (the training cameras: {})",
           train_json.string(), options.camera_id,
           cameras.empty() ? std::string("none given") : fmt::format("{}", fmt::join(cameras, ", ")));
    }
    *what = fmt::format("every frame of camera {}", options.camera_id);
    return chosen;
  }
  std::set<double> times;
  for (const Frame& f : scene.train) times.insert(f.time_raw);
  if (times.size() < 2) {
    Fail("{}: every training frame has the same time; --every-time needs several (hold back a "
         "camera with --camera instead)",
         train_json.string());
  }
  const std::vector<double> sorted(times.begin(), times.end());
  const auto k = static_cast<std::size_t>(options.every_time);
  std::set<double> val_times;
  for (std::size_t i = k / 2; i < sorted.size(); i += k) val_times.insert(sorted[i]);
  if (val_times.empty()) {
    Fail("{}: --every-time {} chooses none of the {} training times (give at most {})",
         train_json.string(), options.every_time, sorted.size(), 2 * sorted.size() - 1);
  }
  for (const Frame& f : scene.train)
    if (val_times.count(f.time_raw)) chosen.insert(f.index);
  *what = fmt::format("every frame at {} of the {} training times (one in {})", val_times.size(),
                      sorted.size(), options.every_time);
  return chosen;
}

}  // namespace

ValSplitSummary SplitOffVal(const fs::path& dir, const fs::path& out, const ValSplitOptions& options) {
  if ((options.every_time > 0) == (options.camera_id >= 0))
    Fail("dataset split-val: give one of --every-time K and --camera ID");
  if (options.every_time == 1)
    Fail("dataset split-val: --every-time 1 would move every training frame; give K >= 2");
  const fs::path train_json = dir / "transforms_train.json";
  const fs::path test_json = dir / "transforms_test.json";
  if (!fs::exists(train_json) || !fs::exists(test_json)) {
    Fail("{}: split-val reads a scene with transforms_train.json and transforms_test.json at its "
         "root (the dataset format); convert other layouts first",
         dir.string());
  }
  const Dataset scene = LoadDataset(dir, {.image_check = ImageCheck::kNone});
  if (!scene.val.empty()) {
    Fail("{}: the scene already has a val split ({} frames); nothing is written",
         (dir / "transforms_val.json").string(), scene.val.size());
  }
  ValSplitSummary summary;
  const std::set<int> chosen = ChooseValFrames(scene, options, train_json, &summary.what);
  nlohmann::json train = ReadJsonFile(train_json);
  const nlohmann::json all = train.at("frames");  // read by LoadDataset: a list
  train["frames"] = nlohmann::json::array();
  nlohmann::json val = train;
  for (std::size_t i = 0; i < all.size(); ++i)
    (chosen.count(static_cast<int>(i)) ? val : train)["frames"].push_back(all[i]);
  summary.moved = val["frames"].size();
  summary.kept = train["frames"].size();
  if (summary.kept == 0) {
    Fail("{}: {} is every training frame; nothing would be left to train on",
         train_json.string(), summary.what);
  }
  StagedFolder staged(out);
  WriteJsonFile(staged.path() / "transforms_train.json", train);
  WriteJsonFile(staged.path() / "transforms_val.json", val);
  try {
    fs::copy_file(test_json, staged.path() / "transforms_test.json");
    // Everything else (images, HDR, point cloud) is the original's, linked rather than copied.
    const std::set<std::string> written = {"transforms_train.json", "transforms_val.json",
                                           "transforms_test.json"};
    for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
      const std::string name = entry.path().filename().string();
      if (written.count(name) || name.front() == '.') continue;
      fs::create_symlink(fs::absolute(entry.path()), staged.path() / name);
    }
  } catch (const fs::filesystem_error& e) {
    Fail("{}: cannot write the new scene: {}", out.string(), e.what());
  }
  staged.Commit();
  return summary;
}

}  // namespace hdr4d
