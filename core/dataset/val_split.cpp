#include "core/dataset/val_split.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <optional>
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

// Which training frames (by their index in their JSON file) go to val, and in words. `file`
// names the scene's file in the errors.
std::set<int> ChooseValFrames(const Dataset& scene,
                              const ValSplitOptions& options,
                              const fs::path& file,
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
      Fail("{}: no training frame has camera_id {} (the training cameras: {})", file.string(),
           options.camera_id,
           cameras.empty() ? std::string("none given; --every-frame K holds back views")
                           : fmt::format("{}", fmt::join(cameras, ", ")));
    }
    *what = fmt::format("every frame of camera {}", options.camera_id);
    return chosen;
  }
  if (options.every_frame > 0) {
    std::vector<int> order;
    for (const Frame& f : scene.train) order.push_back(f.index);
    std::sort(order.begin(), order.end());
    const auto k = static_cast<std::size_t>(options.every_frame);
    for (std::size_t i = k / 2; i < order.size(); i += k) chosen.insert(order[i]);
    if (chosen.empty()) {
      Fail("{}: --every-frame {} chooses none of the {} training frames (give at most {})",
           file.string(), options.every_frame, order.size(), 2 * order.size() - 1);
    }
    *what = fmt::format("{} of the {} training frames (one in {})", chosen.size(), order.size(),
                        options.every_frame);
    return chosen;
  }
  std::set<double> times;
  for (const Frame& f : scene.train) times.insert(f.time_raw);
  if (times.size() < 2) {
    Fail(
        "{}: every training frame has the same time; {} needs several (hold back a "
        "camera or a view instead: --camera ID, --every-frame K)",
        file.string(), options.every_time_flag);
  }
  const std::vector<double> sorted(times.begin(), times.end());
  const auto k = static_cast<std::size_t>(options.every_time);
  std::set<double> val_times;
  for (std::size_t i = k / 2; i < sorted.size(); i += k) val_times.insert(sorted[i]);
  if (val_times.empty()) {
    Fail("{}: {} {} chooses none of the {} training times (give at most {})", file.string(),
         options.every_time_flag, options.every_time, sorted.size(), 2 * sorted.size() - 1);
  }
  for (const Frame& f : scene.train)
    if (val_times.count(f.time_raw)) chosen.insert(f.index);
  *what = fmt::format("every frame at {} of the {} training times (one in {})", val_times.size(),
                      sorted.size(), options.every_time);
  return chosen;
}

// The scene `dir` with the chosen training frames in a val split, as JSON documents to write.
// The reference layout: the new transforms_train.json and transforms_val.json, each with the
// original's top-level keys and every key of each frame. A nerfstudio scene: its one
// transforms.json with the chosen frames' file_path in val_filenames (`nerfstudio` set).
struct PartitionedTrain {
  nlohmann::json train, val;
  std::optional<nlohmann::json> nerfstudio;
  ValSplitSummary summary;
};

// nerfstudio's transforms.json with `chosen` (frame indices) listed in val_filenames. Where the
// file lists no split, its test split is every 8th frame; a list of val frames alone would end
// that (unlisted frames train), so the test frames the loader found are listed too.
nlohmann::json NerfstudioWithVal(const fs::path& file,
                                 const Dataset& scene,
                                 const std::set<int>& chosen) {
  nlohmann::json doc = ReadJsonFile(file);
  const nlohmann::json& frames = doc.at("frames");  // read by LoadDataset: a list
  auto name_of = [&](int index) {
    return frames.at(static_cast<std::size_t>(index)).at("file_path").get<std::string>();
  };
  const bool listed = doc.contains("test_filenames") || doc.contains("train_filenames");
  if (!listed) {
    nlohmann::json test = nlohmann::json::array();
    for (const Frame& f : scene.test) test.push_back(name_of(f.index));
    doc["test_filenames"] = test;
  }
  nlohmann::json val = nlohmann::json::array();
  for (int index : chosen) val.push_back(name_of(index));
  doc["val_filenames"] = val;
  if (doc.contains("train_filenames")) {
    // The loader resolves names against the scene root; compare them as it does.
    std::set<fs::path> moved;
    for (const Frame& f : scene.train)
      if (chosen.count(f.index)) moved.insert(f.image_path);
    nlohmann::json kept = nlohmann::json::array();
    for (const nlohmann::json& name : doc["train_filenames"]) {
      if (!name.is_string() ||
          !moved.count(ResolveImagePath(file.parent_path(), name.get<std::string>())))
        kept.push_back(name);
    }
    doc["train_filenames"] = kept;
  }
  return doc;
}

PartitionedTrain PartitionTrain(const fs::path& dir,
                                const ValSplitOptions& options,
                                const char* who,
                                bool allow_nerfstudio) {
  const int given = (options.every_time > 0) + (options.camera_id >= 0) + (options.every_frame > 0);
  if (given != 1) Fail("{}: give one of --every-time K, --every-frame K and --camera ID", who);
  if (options.every_time == 1)
    Fail("{}: {} 1 would move every training frame; give K >= 2", who, options.every_time_flag);
  if (options.every_frame == 1)
    Fail("{}: --every-frame 1 would move every training frame; give K >= 2", who);
  const fs::path train_json = dir / "transforms_train.json";
  const fs::path test_json = dir / "transforms_test.json";
  const fs::path one_json = dir / "transforms.json";
  const bool reference = fs::exists(train_json) && fs::exists(test_json);
  if (!reference && !(allow_nerfstudio && fs::exists(one_json))) {
    Fail(
        "{}: {} reads a scene with transforms_train.json and transforms_test.json at its "
        "root (the dataset format){}; convert other layouts first",
        dir.string(), who, allow_nerfstudio ? " or nerfstudio's transforms.json" : "");
  }
  const fs::path file = reference ? train_json : one_json;
  const Dataset scene = LoadDataset(dir, {.image_check = ImageCheck::kNone});
  if (!scene.val.empty()) {
    Fail("{}: the scene already has a val split ({} frames); nothing is written",
         (reference ? dir / "transforms_val.json" : one_json).string(), scene.val.size());
  }
  PartitionedTrain p;
  const std::set<int> chosen = ChooseValFrames(scene, options, file, &p.summary.what);
  p.summary.moved = chosen.size();
  p.summary.kept = scene.train.size() - chosen.size();
  if (p.summary.kept == 0) {
    Fail("{}: {} is every training frame; nothing would be left to train on", file.string(),
         p.summary.what);
  }
  if (!reference) {
    p.nerfstudio = NerfstudioWithVal(one_json, scene, chosen);
    return p;
  }
  p.train = ReadJsonFile(train_json);
  const nlohmann::json all = p.train.at("frames");  // read by LoadDataset: a list
  p.train["frames"] = nlohmann::json::array();
  p.val = p.train;
  for (std::size_t i = 0; i < all.size(); ++i)
    (chosen.count(static_cast<int>(i)) ? p.val : p.train)["frames"].push_back(all[i]);
  return p;
}

}  // namespace

ValSplitSummary SplitOffVal(const fs::path& dir,
                            const fs::path& out,
                            const ValSplitOptions& options) {
  const PartitionedTrain p = PartitionTrain(dir, options, "dataset split-val", true);
  StagedFolder staged(out);
  std::set<std::string> written;
  if (p.nerfstudio) {
    WriteJsonFile(staged.path() / "transforms.json", *p.nerfstudio);
    written = {"transforms.json"};
  } else {
    WriteJsonFile(staged.path() / "transforms_train.json", p.train);
    WriteJsonFile(staged.path() / "transforms_val.json", p.val);
    written = {"transforms_train.json", "transforms_val.json", "transforms_test.json"};
  }
  try {
    if (!p.nerfstudio)
      fs::copy_file(dir / "transforms_test.json", staged.path() / "transforms_test.json");
    // Everything else (images, HDR, point cloud) is the original's, linked rather than copied.
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

ValSplitSummary SplitValInPlace(const fs::path& dir,
                                const ValSplitOptions& options,
                                const char* who) {
  const PartitionedTrain p = PartitionTrain(dir, options, who, false);
  // Rewriting the scene's transforms files is this call's job (LoadDataset protected them).
  const OutputPermit permit({dir / "transforms_val.json", dir / "transforms_train.json"});
  // The val file first: a failure between the two writes leaves every frame in train and a
  // val file that repeats some of them, which a folder still being built is thrown away for.
  WriteJsonFile(dir / "transforms_val.json", p.val);
  WriteJsonFile(dir / "transforms_train.json", p.train);
  return p.summary;
}

}  // namespace hdr4d
