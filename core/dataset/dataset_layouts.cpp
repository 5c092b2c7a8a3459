// Which layout a scene folder is: native transforms files, nerfstudio, HDR-NeRF, HDR-GS's COLMAP
// layout, or one hdr4d names but does not read (ARCHITECTURE §3).
#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <set>

#include "core/dataset/colmap_layout.h"
#include "core/dataset/dataset_detail.h"
#include "core/image/image_io.h"

namespace hdr4d::dataset_detail {

bool HasTransforms(const fs::path& root) {
  std::error_code ec;
  return fs::exists(root / "transforms_train.json", ec) || fs::exists(root / "transforms.json", ec);
}

void CheckOtherLayout(const fs::path& root,
                      const DatasetLoadOptions& options,
                      ProblemSink& sink,
                      DatasetReport& report) {
  std::error_code ec;
  const fs::path train_path = root / "transforms_train.json";
  if (IsHdrGsColmapLayout(root)) {
    try {
      report.dataset = ReadHdrGsColmapLayout(root);
      if (options.image_check != ImageCheck::kNone)
        for (const Frame* f : report.dataset->AllFrames()) {
          const ImageSpecInfo spec = ReadImageSpec(f->image_path);
          if (spec.width != f->camera.intrinsics.width ||
              spec.height != f->camera.intrinsics.height)
            sink.Add(
                kRankRoot, f->image_path, -1, "",
                fmt::format("size {}x{} differs from the COLMAP camera's {}x{}", spec.width,
                            spec.height, f->camera.intrinsics.width, f->camera.intrinsics.height));
        }
    } catch (const std::exception& e) {
      sink.Add(kRankRoot, root, -1, "", e.what());
    }
  } else if (fs::is_directory(root / "sparse", ec)) {
    sink.Add(kRankRoot, root, -1, "",
             "a COLMAP layout needs images/ beside sparse/ (as in HDR-GS's synthetic scenes)");
  } else if (fs::exists(root / "poses_bounds_exps.npy", ec)) {
    sink.Add(kRankRoot, root, -1, "",
             "an LLFF layout (poses_bounds_exps.npy, as in HDR-NeRF real scenes) is not "
             "supported yet; convert it to transforms_{train,test}.json");
  } else {
    sink.Add(SplitRank(Split::kTrain, false), train_path, -1, "", "file not found");
  }
}

// nerfstudio's single transforms.json: only undistorted pinhole cameras can be rendered.
void CheckNerfstudioCameraModel(const json& doc, const Reader& r) {
  const auto it = doc.find("camera_model");
  if (it == doc.end()) return;
  if (!it->is_string()) {
    r.Problem(-1, "camera_model", "expected a string, got " + Describe(*it));
    return;
  }
  const std::string model = it->get<std::string>();
  if (model == "PINHOLE" || model == "SIMPLE_PINHOLE") return;
  if (model == "OPENCV") {
    // The coefficients may be given for the file or per frame (nerfstudio reads both).
    const auto distorted = [&](const json& obj, int frame) {
      for (const char* key : {"k1", "k2", "k3", "k4", "p1", "p2"}) {
        const auto k = obj.find(key);
        if (k == obj.end() || (k->is_number() && k->get<double>() == 0.0)) continue;
        r.Problem(frame, key,
                  "lens distortion is not supported (hdr4d renders pinhole cameras); undistort "
                  "the images first");
        return true;
      }
      return false;
    };
    if (distorted(doc, -1)) return;
    const auto frames = doc.find("frames");
    if (frames == doc.end() || !frames->is_array()) return;
    for (std::size_t i = 0; i < frames->size(); ++i)
      if ((*frames)[i].is_object() && distorted((*frames)[i], static_cast<int>(i))) return;
    return;
  }
  r.Problem(-1, "camera_model",
            fmt::format("'{}' is not supported (hdr4d renders pinhole cameras); use PINHOLE or "
                        "undistort the images first",
                        model));
}

// Splits nerfstudio's one file: test_filenames / val_filenames when given, else every 8th
// frame (index % 8 == 0) is held out for test, the convention of the 3DGS evaluation.
void SplitNerfstudio(const fs::path& root,
                     const json& doc,
                     const Reader& r,
                     std::array<SplitFile, 3>& files) {
  struct ListedAs {
    Split split;
    const char* key;   // the list that names it
    std::string name;  // as written there
  };
  std::map<fs::path, ListedAs> listed;
  bool any_list = false;
  for (const auto& [key, split] :
       {std::pair{"test_filenames", Split::kTest}, std::pair{"val_filenames", Split::kVal},
        std::pair{"train_filenames", Split::kTrain}}) {
    const auto it = doc.find(key);
    if (it == doc.end()) continue;
    any_list = true;
    if (!it->is_array()) {
      r.Problem(-1, key, "expected a list of file paths, got " + Describe(*it));
      continue;
    }
    for (const json& name : *it) {
      if (!name.is_string()) {
        r.Problem(-1, key, "expected file path strings, got " + Describe(name));
        continue;
      }
      const auto [at, added] = listed.emplace(ResolveImagePath(root, name.get<std::string>()),
                                              ListedAs{split, key, name.get<std::string>()});
      if (!added)
        r.Problem(-1, key, fmt::format("'{}' is listed in {} too: a frame has one split",
                                       name.get<std::string>(), at->second.key));
    }
  }
  // A listed name that is no frame's image (nerfstudio itself refuses it): its frame would be
  // trained on instead of held out.
  std::set<fs::path> images;
  for (const PendingFrame& p : files[0].frames) images.insert(p.frame.image_path);
  for (const auto& [path, as] : listed)
    if (!images.count(path))
      r.Problem(-1, as.key, fmt::format("'{}' is no frame's file_path", as.name));
  std::vector<PendingFrame> all = std::move(files[0].frames);
  files[0].frames.clear();
  for (PendingFrame& p : all) {
    Split split = Split::kTrain;
    if (any_list) {
      const auto it = listed.find(p.frame.image_path);
      if (it != listed.end()) split = it->second.split;
    } else if (p.frame.index % 8 == 0) {
      split = Split::kTest;
    }
    p.frame.split = split;
    files[static_cast<int>(split)].frames.push_back(std::move(p));
  }
  for (int s = 1; s < 3; ++s) {
    files[s].camera_angle_x = files[0].camera_angle_x;
    files[s].near = files[0].near;
    files[s].far = files[0].far;
    files[s].parsed = true;
  }
}

std::string LayoutName(const SceneFiles& scene, const Dataset& dataset) {
  const bool any_exposure = std::any_of(dataset.train.begin(), dataset.train.end(),
                                        [](const Frame& f) { return f.exposure_given; }) ||
                            std::any_of(dataset.test.begin(), dataset.test.end(),
                                        [](const Frame& f) { return f.exposure_given; }) ||
                            std::any_of(dataset.val.begin(), dataset.val.end(),
                                        [](const Frame& f) { return f.exposure_given; });
  return scene.nerfstudio ? "nerfstudio"
         : scene.hdrnerf  ? "hdrnerf"
         : any_exposure   ? "hdr4d"
                          : "dnerf";
}

}  // namespace hdr4d::dataset_detail
