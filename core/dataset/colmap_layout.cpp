#include "core/dataset/colmap_layout.h"

#include <fmt/format.h>

#include <algorithm>
#include <regex>

#include "core/geometry/colmap_model.h"
#include "core/util/error.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {
constexpr double kHdrGsExposures[] = {0.125, 0.5, 2.0, 8.0, 32.0};
constexpr int kHdrGsTrainExposures[] = {0, 2, 4};
}  // namespace

bool IsHdrGsColmapLayout(const fs::path& root) {
  std::error_code ec;
  return fs::is_directory(root / "sparse", ec) && fs::is_directory(root / "images", ec) &&
         !fs::exists(root / "transforms_train.json", ec) && !fs::exists(root / "transforms.json", ec);
}

Dataset ReadHdrGsColmapLayout(const fs::path& root) {
  const fs::path folder = FindColmapModelFolder(root);
  const ColmapModel model = ReadColmapModel(folder);
  struct View {
    std::string name;
    const ColmapImage* image;
  };
  std::vector<View> views;
  const std::regex suffix(R"(^(.*)_\d+$)");
  for (const auto& [id, image] : model.images) {
    std::string stem = fs::path(image.name).stem().string();
    std::smatch m;
    if (std::regex_match(stem, m, suffix)) stem = m[1];
    if (std::none_of(views.begin(), views.end(), [&](const View& v) { return v.name == stem; }))
      views.push_back({stem, &image});
  }
  if (views.empty()) Fail("{}: the COLMAP model has no images", folder.string());
  std::sort(views.begin(), views.end(), [](const View& a, const View& b) { return a.name < b.name; });

  Dataset dataset;
  dataset.root = root;
  dataset.layout = "hdrgs-colmap";
  std::error_code ec;
  if (fs::exists(root / "point3d.ply", ec)) dataset.point_cloud_path = root / "point3d.ply";
  for (std::size_t v = 0; v < views.size(); ++v) {
    const ColmapCamera& colmap_camera = model.cameras.at(views[v].image->camera_id);
    Eigen::Vector2d tangential;
    if (colmap_camera.Radial(&tangential).norm() > 0 || tangential.norm() > 0)
      Fail("{}: camera {} has lens distortion ({}); hdr4d renders pinhole cameras, undistort the "
           "images first", folder.string(), colmap_camera.id, colmap_camera.model);
    const PinholeIntrinsics intrinsics = colmap_camera.Pinhole();
    if (const std::string problem = intrinsics.Problem(); !problem.empty())
      Fail("{}: camera {}: {}", folder.string(), colmap_camera.id, problem);
    const Camera camera =
        Camera::FromWorldFromCamCv(intrinsics, RigidInverse(views[v].image->CamFromWorldCv()));
    const std::string ext = fs::path(views[v].image->name).extension().string();
    const bool test = v % 2 == 1;
    for (int k = 0; k < 5; ++k) {
      if (!test && std::find(std::begin(kHdrGsTrainExposures), std::end(kHdrGsTrainExposures), k) ==
                       std::end(kHdrGsTrainExposures))
        continue;
      Frame frame;
      frame.split = test ? Split::kTest : Split::kTrain;
      frame.file_path = fmt::format("images/{}_{}{}", views[v].name, k, ext.empty() ? ".png" : ext);
      frame.image_path = root / frame.file_path;
      if (!fs::exists(frame.image_path, ec))
        Fail("{}: view {} exposure {}: image not found", frame.image_path.string(), views[v].name, k);
      const std::string exr = fmt::format("exr/{}.exr", views[v].name);
      if (fs::exists(root / exr, ec)) {
        frame.exr_file_path = exr;
        frame.hdr_path = root / exr;
      }
      frame.exposure = kHdrGsExposures[k];
      frame.exposure_given = true;
      frame.exposure_index = k;
      frame.camera_id = static_cast<int>(v);
      frame.camera = camera;
      auto& list = test ? dataset.test : dataset.train;
      frame.index = static_cast<int>(list.size());
      list.push_back(std::move(frame));
    }
  }
  if (dataset.train.empty()) Fail("{}: no training views", root.string());
  dataset.camera_angle_x = dataset.train.front().camera.intrinsics.FovX();
  return dataset;
}

}  // namespace hdr4d
