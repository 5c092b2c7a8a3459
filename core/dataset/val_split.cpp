#include "core/dataset/val_split.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <set>
#include <vector>

#include "core/dataset/dataset.h"
#include "core/files/json_util.h"
#include "core/files/output_guard.h"
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
    Fail("{}: every training frame has the same time; {} needs several (hold back a "
         "camera instead)",
         train_json.string(), options.every_time_flag);
  }
  const std::vector<double> sorted(times.begin(), times.end());
  const auto k = static_cast<std::size_t>(options.every_time);
  std::set<double> val_times;
  for (std::size_t i = k / 2; i < sorted.size(); i += k) val_times.insert(sorted[i]);
  if (val_times.empty()) {
    Fail("{}: {} {} chooses none of the {} training times (give at most {})", train_json.string(),
         options.every_time_flag, options.every_time, sorted.size(), 2 * sorted.size() - 1);
  }
  for (const Frame& f : scene.train)
    if (val_times.count(f.time_raw)) chosen.insert(f.index);
  *what = fmt::format("every frame at {} of the {} training times (one in {})", val_times.size(),
                      sorted.size(), options.every_time);
  return chosen;
}

// The chosen training frames of `dir`, as the new train and val JSON documents: each keeps the
// original's top-level keys and every key of each frame.
struct PartitionedTrain {
  nlohmann::json train, val;
  ValSplitSummary summary;
};

PartitionedTrain PartitionTrain(const fs::path& dir, const ValSplitOptions& options,
                                const char* who) {
  if ((options.every_time > 0) == (options.camera_id >= 0))
    Fail("{}: give one of --every-time K and --camera ID", who);
  if (options.every_time == 1)
    Fail("{}: {} 1 would move every training frame; give K >= 2", who, options.every_time_flag);
  const fs::path train_json = dir / "transforms_train.json";
  const fs::path test_json = dir / "transforms_test.json";
  if (!fs::exists(train_json) || !fs::exists(test_json)) {
    Fail("{}: {} reads a scene with transforms_train.json and transforms_test.json at its "
         "root (the dataset format); convert other layouts first",
         dir.string(), who);
  }
  const Dataset scene = LoadDataset(dir, {.image_check = ImageCheck::kNone});
  if (!scene.val.empty()) {
    Fail("{}: the scene already has a val split ({} frames); nothing is written",
         (dir / "transforms_val.json").string(), scene.val.size());
  }
  PartitionedTrain p;
  const std::set<int> chosen = ChooseValFrames(scene, options, train_json, &p.summary.what);
  p.train = ReadJsonFile(train_json);
  const nlohmann::json all = p.train.at("frames");  // read by LoadDataset: a list
  p.train["frames"] = nlohmann::json::array();
  p.val = p.train;
  for (std::size_t i = 0; i < all.size(); ++i)
    (chosen.count(static_cast<int>(i)) ? p.val : p.train)["frames"].push_back(all[i]);
  p.summary.moved = p.val["frames"].size();
  p.summary.kept = p.train["frames"].size();
  if (p.summary.kept == 0) {
    Fail("{}: {} is every training frame; nothing would be left to train on",
         train_json.string(), p.summary.what);
  }
  return p;
}

}  // namespace

ValSplitSummary SplitOffVal(const fs::path& dir, const fs::path& out, const ValSplitOptions& options) {
  const PartitionedTrain p = PartitionTrain(dir, options, "dataset split-val");
  StagedFolder staged(out);
  WriteJsonFile(staged.path() / "transforms_train.json", p.train);
  WriteJsonFile(staged.path() / "transforms_val.json", p.val);
  try {
    fs::copy_file(dir / "transforms_test.json", staged.path() / "transforms_test.json");
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
  return p.summary;
}

ValSplitSummary SplitValInPlace(const fs::path& dir, const ValSplitOptions& options,
                                const char* who) {
  const PartitionedTrain p = PartitionTrain(dir, options, who);
  // Rewriting the scene's transforms files is this call's job (LoadDataset protected them).
  const OutputPermit permit({dir / "transforms_val.json", dir / "transforms_train.json"});
  // The val file first: a failure between the two writes leaves every frame in train and a
  // val file that repeats some of them, which a folder still being built is thrown away for.
  WriteJsonFile(dir / "transforms_val.json", p.val);
  WriteJsonFile(dir / "transforms_train.json", p.train);
  return p.summary;
}

}  // namespace hdr4d
