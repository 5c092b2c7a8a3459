#include "core/dataset/dataset_checksum.h"

#include <fmt/format.h>

#include <map>
#include <set>

#include "core/files/sha256.h"
#include "core/util/error.h"

namespace hdr4d {
namespace fs = std::filesystem;

std::vector<std::pair<fs::path, std::string>> HashDatasetFiles(const Dataset& dataset) {
  const fs::path& dir = dataset.root;
  std::set<fs::path> files;
  for (const char* name : {"transforms_train.json", "transforms_test.json", "transforms_val.json",
                           "transforms.json", "point3d.ply"}) {
    if (fs::exists(dir / name)) files.insert(dir / name);
  }
  for (const Frame* f : dataset.AllFrames()) {
    files.insert(f->image_path);
    if (f->hdr_path) files.insert(*f->hdr_path);
  }
  std::vector<std::pair<fs::path, std::string>> hashes;
  for (const fs::path& f : files) hashes.emplace_back(f, fs::exists(f) ? Sha256File(f) : "absent");
  return hashes;
}

namespace {

// "train images/x.png", split by split, in the JSON's order.
std::vector<std::string> FrameNames(const Dataset& dataset) {
  std::vector<std::string> frames;
  for (const Frame* f : dataset.AllFrames())
    frames.push_back(fmt::format("{} {}", SplitName(f->split), f->file_path));
  return frames;
}

}  // namespace

nlohmann::json DatasetRecord::ToJson() const {
  nlohmann::json j_files = nlohmann::json::object();
  for (const auto& [path, hash] : files) j_files[path] = hash;
  return {{"frames", frames}, {"sha256", j_files}};
}

DatasetRecord DatasetRecord::FromJson(const nlohmann::json& json, const std::string& source) {
  DatasetRecord r;
  if (!json.is_object() || !json.contains("frames") || !json["frames"].is_array() ||
      !json.contains("sha256") || !json["sha256"].is_object())
    Fail("{}: not a record of a run's data (expected \"frames\" and \"sha256\")", source);
  for (const auto& f : json["frames"]) {
    if (!f.is_string()) Fail("{}: \"frames\" holds a value that is not a string", source);
    r.frames.push_back(f.get<std::string>());
  }
  for (const auto& [path, hash] : json["sha256"].items()) {
    if (!hash.is_string()) Fail("{}: \"sha256\" of {} is not a string", source, path);
    r.files.emplace_back(path, hash.get<std::string>());
  }
  return r;
}

DatasetRecord RecordDataset(const Dataset& dataset) {
  DatasetRecord r;
  r.frames = FrameNames(dataset);
  for (const auto& [path, hash] : HashDatasetFiles(dataset))
    r.files.emplace_back(path.lexically_relative(dataset.root).generic_string(), hash);
  return r;
}

std::string DescribeCameraChange(const DatasetRecord& before, const Dataset& now) {
  DatasetRecord json_before, json_now;
  json_before.frames = before.frames;
  json_now.frames = FrameNames(now);
  for (const auto& [path, hash] : before.files) {
    if (fs::path(path).extension() != ".json") continue;
    json_before.files.emplace_back(path, hash);
    const fs::path file = now.root / path;
    json_now.files.emplace_back(path, fs::exists(file) ? Sha256File(file) : "absent");
  }
  return DescribeDatasetChange(json_before, json_now);
}

std::string DescribeDatasetChange(const DatasetRecord& before, const DatasetRecord& now) {
  if (before.frames.size() != now.frames.size()) {
    return fmt::format("it had {} frames when the run started and has {} now",
                       before.frames.size(), now.frames.size());
  }
  for (std::size_t i = 0; i < before.frames.size(); ++i) {
    if (before.frames[i] != now.frames[i]) {
      return fmt::format("frame {} was '{}' when the run started and is '{}' now (frames "
                         "reordered, renamed or replaced)",
                         i, before.frames[i], now.frames[i]);
    }
  }
  const std::map<std::string, std::string> now_files(now.files.begin(), now.files.end());
  for (const auto& [path, hash] : before.files) {
    const auto it = now_files.find(path);
    if (it == now_files.end()) return fmt::format("{} is no longer part of it", path);
    if (it->second != hash) return fmt::format("{} changed (its SHA-256 differs)", path);
  }
  return "";
}

}  // namespace hdr4d
