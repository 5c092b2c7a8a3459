#include "calibration/rig_geometry.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <map>

#include "calibration/undistort.h"
#include "core/util/error.h"
#include "core/files/json_util.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

std::string FolderOf(const std::string& image_name) {
  const auto slash = image_name.find('/');
  return slash == std::string::npos ? std::string() : image_name.substr(0, slash);
}

BundleIntrinsics IntrinsicsOf(const ColmapCamera& camera) {
  const PinholeIntrinsics k = camera.Pinhole();
  const Eigen::Vector2d radial = camera.Radial();
  return {0.5 * (k.fx + k.fy), k.cx, k.cy, radial.x(), radial.y()};
}

BundlePose PoseOf(const ColmapImage& image) {
  BundlePose pose;
  const Eigen::AngleAxisd aa(image.cam_from_world_rotation.normalized());
  pose.rotation = aa.angle() * aa.axis();
  pose.translation = image.cam_from_world_translation;
  return pose;
}

double Percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  const std::size_t i = static_cast<std::size_t>(q * (values.size() - 1));
  std::nth_element(values.begin(), values.begin() + i, values.end());
  return values[i];
}

}  // namespace

const RigCamera* Rig::Find(const std::string& name) const {
  for (const RigCamera& c : cameras)
    if (c.name == name) return &c;
  return nullptr;
}

Rig RigFromColmap(const ColmapModel& model, const std::vector<std::string>& camera_names,
                  const RigOptions& options) {
  Rig rig;
  BundleProblem problem;
  std::map<int, int> pose_of_image;        // COLMAP image id -> bundle pose
  std::map<int, int> intrinsics_of_camera;  // COLMAP camera id -> bundle intrinsics
  auto intrinsics_index = [&](int camera_id) {
    auto [it, added] = intrinsics_of_camera.emplace(camera_id, static_cast<int>(problem.intrinsics.size()));
    if (added) problem.intrinsics.push_back(IntrinsicsOf(model.cameras.at(camera_id)));
    return it->second;
  };
  std::vector<int> rig_intrinsics;
  // Rig cameras first (pose i = camera i), all their images sharing one pose.
  for (std::size_t c = 0; c < camera_names.size(); ++c) {
    RigCamera camera;
    camera.name = camera_names[c];
    int first = -1;
    for (const auto& [id, image] : model.images) {
      if (FolderOf(image.name) != camera.name) continue;
      if (first < 0) {
        first = id;
        problem.poses.push_back(PoseOf(image));
        problem.poses.back().fixed = c == 0;  // the gauge
      }
      pose_of_image[id] = static_cast<int>(c);
      ++camera.static_images_registered;
    }
    if (first < 0)
      Fail("camera {}: none of its static images (static/{}/) was registered by COLMAP; it "
           "needs views that overlap the other cameras'", camera.name, camera.name);
    const ColmapCamera& colmap_camera = model.cameras.at(model.images.at(first).camera_id);
    camera.width = colmap_camera.width;
    camera.height = colmap_camera.height;
    if (const auto board = options.board_intrinsics.find(camera.name); board != options.board_intrinsics.end()) {
      // Its own block, held: the board's intrinsics are the better measurement.
      rig_intrinsics.push_back(static_cast<int>(problem.intrinsics.size()));
      problem.intrinsics.push_back(board->second);
      problem.intrinsics.back().fixed = true;
      camera.board_intrinsics = true;
    } else {
      rig_intrinsics.push_back(intrinsics_index(colmap_camera.id));
    }
    rig.cameras.push_back(camera);
  }
  // Extra (hand-held) images: a pose each; they constrain the points and are then dropped.
  for (const auto& [id, image] : model.images) {
    if (pose_of_image.count(id)) continue;
    pose_of_image[id] = static_cast<int>(problem.poses.size());
    problem.poses.push_back(PoseOf(image));
    ++rig.extra_images_registered;
  }
  std::vector<std::int64_t> point_ids;
  for (const auto& [id, point] : model.points) {
    const int index = static_cast<int>(problem.points.size());
    problem.points.push_back(point.xyz);
    point_ids.push_back(id);
    rig.visibility.emplace_back();
    for (const auto& [image_id, idx] : point.track) {
      const ColmapImage& image = model.images.at(image_id);
      const int pose = pose_of_image.at(image_id);
      if (pose < static_cast<int>(camera_names.size()) &&
          std::find(rig.visibility.back().begin(), rig.visibility.back().end(), pose) == rig.visibility.back().end())
        rig.visibility.back().push_back(pose);
      const int k = pose < static_cast<int>(camera_names.size()) ? rig_intrinsics[pose]
                                                                 : intrinsics_index(image.camera_id);
      problem.observations.push_back({pose, k, index, image.points2d[idx]});
    }
  }
  if (problem.observations.empty()) Fail("COLMAP's model has no 3D points to refine the rig with");

  const BundleReport report = RefineBundle(&problem);
  rig.refinement_iterations = report.iterations;

  // Normalise: the median point to the origin, 90% of the points within radius 1.
  std::vector<double> coords[3], radii;
  for (const auto& p : problem.points)
    for (int a = 0; a < 3; ++a) coords[a].push_back(p[a]);
  for (int a = 0; a < 3; ++a) rig.centre[a] = Percentile(coords[a], 0.5);
  for (const auto& p : problem.points) radii.push_back((p - rig.centre).norm());
  const double r90 = Percentile(radii, 0.9);
  rig.scale = r90 > 1e-12 ? 1.0 / r90 : 1.0;

  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    RigCamera& camera = rig.cameras[c];
    const BundlePose& pose = problem.poses[c];
    camera.intrinsics = problem.intrinsics[rig_intrinsics[c]];
    camera.rms_before = report.rms_before[c];
    camera.rms_after = report.rms_after[c];
    camera.observations = report.observations[c];
    const double angle = pose.rotation.norm();
    const Eigen::Matrix3d r = angle > 0 ? Eigen::AngleAxisd(angle, pose.rotation / angle).toRotationMatrix()
                                        : Eigen::Matrix3d::Identity();
    Eigen::Matrix4d cam_from_world = Eigen::Matrix4d::Identity();
    cam_from_world.topLeftCorner<3, 3>() = r;
    cam_from_world.topRightCorner<3, 1>() = rig.scale * (r * rig.centre + pose.translation);
    const Camera cam = Camera::FromWorldFromCamCv(
        PinholeIntrinsics{camera.intrinsics.f, camera.intrinsics.f, camera.intrinsics.cx,
                          camera.intrinsics.cy, camera.width, camera.height},
        RigidInverse(cam_from_world));
    camera.world_from_cam_gl = cam.world_from_cam_gl;
    camera.max_distortion_pixels = MaxDistortionPixels(camera.intrinsics, camera.width, camera.height);
    camera.undistort = camera.max_distortion_pixels > options.undistort_threshold_pixels;
  }
  for (std::size_t i = 0; i < problem.points.size(); ++i) {
    rig.points.positions.push_back(((problem.points[i] - rig.centre) * rig.scale).cast<float>());
    rig.points.colors.push_back(model.points.at(point_ids[i]).rgb);
  }
  return rig;
}

void WriteRigJson(const fs::path& path, const Rig& rig) {
  nlohmann::json doc;
  doc["model_source"] = rig.model_source;
  doc["intrinsics_source"] = rig.intrinsics_source;
  doc["metres_per_unit"] = rig.metres_per_unit;
  doc["normalisation"] = {{"centre", {rig.centre.x(), rig.centre.y(), rig.centre.z()}},
                          {"scale", rig.scale}};
  doc["extra_images_registered"] = rig.extra_images_registered;
  doc["refinement_iterations"] = rig.refinement_iterations;
  for (const RigCamera& c : rig.cameras) {
    nlohmann::json m = nlohmann::json::array();
    for (int r = 0; r < 4; ++r) m.push_back({c.world_from_cam_gl(r, 0), c.world_from_cam_gl(r, 1),
                                             c.world_from_cam_gl(r, 2), c.world_from_cam_gl(r, 3)});
    doc["cameras"].push_back({{"name", c.name},
                              {"width", c.width},
                              {"height", c.height},
                              {"f", c.intrinsics.f},
                              {"cx", c.intrinsics.cx},
                              {"cy", c.intrinsics.cy},
                              {"k1", c.intrinsics.k1},
                              {"k2", c.intrinsics.k2},
                              {"transform_matrix", m},
                              {"rms_before", c.rms_before},
                              {"rms_after", c.rms_after},
                              {"observations", c.observations},
                              {"static_images_registered", c.static_images_registered},
                              {"max_distortion_pixels", c.max_distortion_pixels},
                              {"undistort", c.undistort},
                              {"board_intrinsics", c.board_intrinsics}});
  }
  WriteJsonFile(path, doc);
}

Rig ReadRigJson(const fs::path& path) {
  const nlohmann::json doc = ReadJsonFile(path);
  Rig rig;
  try {
    rig.model_source = doc.at("model_source").get<std::string>();
    rig.intrinsics_source = doc.value("intrinsics_source", rig.intrinsics_source);
    rig.metres_per_unit = doc.value("metres_per_unit", 0.0);
    const auto& n = doc.at("normalisation");
    for (int a = 0; a < 3; ++a) rig.centre[a] = n.at("centre").at(a).get<double>();
    rig.scale = n.at("scale").get<double>();
    rig.extra_images_registered = doc.value("extra_images_registered", 0);
    rig.refinement_iterations = doc.value("refinement_iterations", 0);
    for (const auto& j : doc.at("cameras")) {
      RigCamera c;
      c.name = j.at("name").get<std::string>();
      c.width = j.at("width").get<int>();
      c.height = j.at("height").get<int>();
      c.intrinsics = {j.at("f").get<double>(), j.at("cx").get<double>(), j.at("cy").get<double>(),
                      j.at("k1").get<double>(), j.at("k2").get<double>()};
      for (int r = 0; r < 4; ++r)
        for (int k = 0; k < 4; ++k) c.world_from_cam_gl(r, k) = j.at("transform_matrix").at(r).at(k).get<double>();
      c.rms_before = j.at("rms_before").get<double>();
      c.rms_after = j.at("rms_after").get<double>();
      c.observations = j.at("observations").get<int>();
      c.static_images_registered = j.at("static_images_registered").get<int>();
      c.max_distortion_pixels = j.at("max_distortion_pixels").get<double>();
      c.undistort = j.at("undistort").get<bool>();
      c.board_intrinsics = j.value("board_intrinsics", false);
      rig.cameras.push_back(c);
    }
  } catch (const nlohmann::json::exception& e) {
    Fail("{}: {}", path.string(), e.what());
  }
  return rig;
}

}  // namespace hdr4d
