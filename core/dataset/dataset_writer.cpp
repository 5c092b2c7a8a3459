// WriteDataset (declared in core/dataset/dataset.h): the inverse of LoadDataset for the JSON files.
#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>

#include "core/dataset/dataset.h"
#include "core/util/error.h"
#include "core/files/json_util.h"

namespace hdr4d {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Same value up to the last few bits of a double (intrinsics that went through tan/atan).
bool Same(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(1.0, std::abs(a)); }

bool SameIntrinsics(const PinholeIntrinsics& a, const PinholeIntrinsics& b) {
  return a.width == b.width && a.height == b.height && Same(a.fx, b.fx) && Same(a.fy, b.fy) &&
         Same(a.cx, b.cx) && Same(a.cy, b.cy);
}

// All six keys: partial keys would be resolved through defaults (fl_y from fl_x, cx from w)
// that need not give back the same values.
void PutIntrinsics(json& obj, const PinholeIntrinsics& k) {
  obj["fl_x"] = k.fx;
  obj["fl_y"] = k.fy;
  obj["cx"] = k.cx;
  obj["cy"] = k.cy;
  obj["w"] = k.width;
  obj["h"] = k.height;
}

std::string RelativeTo(const fs::path& root, const fs::path& path) {
  if (path.is_relative()) return path.generic_string();
  return path.lexically_relative(root).generic_string();
}

// camera_angle_x: the dataset's, else the first frame's field of view.
double CameraAngleX(const Dataset& dataset,
                    const std::vector<const Frame*>& all,
                    const fs::path& root) {
  double angle = dataset.camera_angle_x;
  if (!(angle > 0 && angle < std::numbers::pi) && !all.empty()) {
    angle = all.front()->camera.intrinsics.FovX();
  }
  if (!(angle > 0 && angle < std::numbers::pi)) {
    Fail("{}: cannot write a dataset without a valid camera_angle_x (got {})", root.string(),
         angle);
  }
  return angle;
}

// The top level's keys, and what a frame without keys gets when read back (none without a
// shared top level).
struct TopLevel {
  json keys = json::object();
  std::optional<PinholeIntrinsics> intrinsics;
};

// What every frame shares (size, then intrinsics when they are not the ones camera_angle_x
// implies); frames that differ carry their own keys.
TopLevel SharedTopLevel(const std::vector<const Frame*>& all, double angle) {
  bool same_size = !all.empty(), same_intrinsics = !all.empty();
  for (const Frame* f : all) {
    const PinholeIntrinsics& k = f->camera.intrinsics;
    const PinholeIntrinsics& first = all.front()->camera.intrinsics;
    same_size = same_size && k.width == first.width && k.height == first.height;
    same_intrinsics = same_intrinsics && SameIntrinsics(k, first);
  }
  TopLevel top;
  if (same_size) {
    const PinholeIntrinsics& first = all.front()->camera.intrinsics;
    const PinholeIntrinsics implied = PinholeIntrinsics::FromFovX(angle, first.width, first.height);
    top.intrinsics = implied;
    top.keys["w"] = first.width;
    top.keys["h"] = first.height;
    if (same_intrinsics && !SameIntrinsics(first, implied)) {
      PutIntrinsics(top.keys, first);
      top.intrinsics = first;
    }
  }
  return top;
}

// Frame `i` of the split file `path`; a value the reader would refuse fails naming the file,
// the frame and the key.
json FrameJson(const Frame& f,
               std::size_t i,
               const fs::path& path,
               const fs::path& root,
               double angle,
               const std::optional<PinholeIntrinsics>& top) {
  const auto fail = [&](const char* key, const std::string& why) {
    Fail("{}: frame {}: {}: {}", path.string(), i, key, why);
  };
  json obj;
  std::string file_path = f.file_path;
  if (file_path.empty() && !f.image_path.empty()) file_path = RelativeTo(root, f.image_path);
  if (file_path.empty()) fail("file_path", "empty (set file_path or image_path)");
  obj["file_path"] = file_path;

  const std::string pose_problem = PoseProblem(f.camera.world_from_cam_gl);
  if (!pose_problem.empty()) fail("transform_matrix", pose_problem);
  json rows = json::array();
  for (int r = 0; r < 4; ++r) {
    rows.push_back({f.camera.world_from_cam_gl(r, 0), f.camera.world_from_cam_gl(r, 1),
                    f.camera.world_from_cam_gl(r, 2), f.camera.world_from_cam_gl(r, 3)});
  }
  obj["transform_matrix"] = rows;

  if (!(std::isfinite(f.time_raw) && f.time_raw >= 0)) {
    fail("time", fmt::format("must be finite and not negative, got {}", f.time_raw));
  }
  obj["time"] = f.time_raw;
  if (f.exposure_given) {
    if (!(std::isfinite(f.exposure) && f.exposure > 0)) {
      fail("exposures", fmt::format("must be positive and finite, got {}", f.exposure));
    }
    obj["exposures"] = f.exposure;
  }
  std::string exr = f.exr_file_path.value_or("");
  if (exr.empty() && f.hdr_path) exr = RelativeTo(root, *f.hdr_path);
  if (!exr.empty()) obj["exr_file_path"] = exr;
  if (f.camera_id >= 0) obj["camera_id"] = f.camera_id;
  if (f.exposure_index >= 0) obj["exposure_index"] = f.exposure_index;

  const PinholeIntrinsics& k = f.camera.intrinsics;
  if (std::string problem = k.Problem(); !problem.empty()) fail("intrinsics", problem);
  // Without a shared top level, the reader falls back on camera_angle_x at the frame's size.
  const PinholeIntrinsics base = top ? *top : PinholeIntrinsics::FromFovX(angle, k.width, k.height);
  if (!SameIntrinsics(k, base)) {
    PutIntrinsics(obj, k);
  } else if (!top) {
    obj["w"] = k.width;
    obj["h"] = k.height;
  }
  return obj;
}

}  // namespace

void WriteDataset(const Dataset& dataset,
                  const fs::path& root,
                  const DatasetWriteOptions& options) {
  const std::vector<const Frame*> all = dataset.AllFrames();
  const double angle = CameraAngleX(dataset, all, root);
  const TopLevel top = SharedTopLevel(all, angle);
  std::vector<Split> splits = {Split::kTrain, Split::kTest};
  if (options.write_val && !dataset.val.empty()) splits.push_back(Split::kVal);
  for (Split split : splits) {
    const fs::path path = root / fmt::format("transforms_{}.json", SplitName(split));
    json doc = top.keys;
    doc["camera_angle_x"] = angle;
    if (dataset.near) doc["near"] = *dataset.near;
    if (dataset.far) doc["far"] = *dataset.far;
    json frames = json::array();
    const std::vector<Frame>& split_frames = dataset.FramesOf(split);
    for (std::size_t i = 0; i < split_frames.size(); ++i)
      frames.push_back(FrameJson(split_frames[i], i, path, root, angle, top.intrinsics));
    doc["frames"] = std::move(frames);
    WriteJsonFile(path, doc);
  }
}

void RebaseDataset(Dataset* dataset, const fs::path& new_root) {
  const fs::path old_root = dataset->root;
  auto move = [&](fs::path& p) {
    if (!p.empty()) p = new_root / p.lexically_relative(old_root);
  };
  for (std::vector<Frame>* split : {&dataset->train, &dataset->test, &dataset->val}) {
    for (Frame& f : *split) {
      move(f.image_path);
      if (f.hdr_path) move(*f.hdr_path);
    }
  }
  if (dataset->point_cloud_path) move(*dataset->point_cloud_path);
  dataset->root = new_root;
}

}  // namespace hdr4d
