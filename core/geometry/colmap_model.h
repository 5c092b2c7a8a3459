// COLMAP sparse models (cameras, images, points3D) in both of COLMAP's formats: binary
// (cameras.bin, images.bin, points3D.bin) and text (cameras.txt, ...). Read by
// `hdr4d calibrate` after its COLMAP run (or from a user's --colmap-model) and written by tests
// and datagen's capture mode. Poses are COLMAP's: cam_from_world in OpenCV axes.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/geometry/camera.h"

namespace hdr4d {

// COLMAP's camera models with their parameter counts; the ones hdr4d can turn into a pinhole
// camera with radial distortion are SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL and OPENCV.
struct ColmapCamera {
  int id = 0;
  std::string model;  // "PINHOLE", "SIMPLE_RADIAL", ...
  int width = 0, height = 0;
  std::vector<double> params;  // in COLMAP's order for the model

  // fx, fy, cx, cy; throws hdr4d::Error for a model hdr4d cannot use.
  PinholeIntrinsics Pinhole() const;
  // k1, k2 (0 where the model has none); p1/p2 of OPENCV are returned through `tangential`.
  Eigen::Vector2d Radial(Eigen::Vector2d* tangential = nullptr) const;
};

struct ColmapImage {
  int id = 0;
  int camera_id = 0;
  std::string name;                                        // relative to the image folder
  Eigen::Quaterniond cam_from_world_rotation{1, 0, 0, 0};  // qw, qx, qy, qz
  Eigen::Vector3d cam_from_world_translation = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector2d> points2d;
  std::vector<std::int64_t> point3d_ids;  // one per points2d, -1 = not triangulated

  Eigen::Matrix4d CamFromWorldCv() const;
};

struct ColmapPoint {
  std::int64_t id = 0;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  Eigen::Vector3f rgb = Eigen::Vector3f::Zero();  // [0,1]
  double error = 0;
  std::vector<std::pair<int, int>> track;  // (image id, index into its points2d)
};

struct ColmapModel {
  std::map<int, ColmapCamera> cameras;
  std::map<int, ColmapImage> images;
  std::map<std::int64_t, ColmapPoint> points;
};

// The number of parameters of a COLMAP camera model name, or -1 for an unknown one.
int ColmapModelParamCount(const std::string& model);

// Reads the model in `folder`: the .bin files when cameras.bin is there, else the .txt files.
// Throws hdr4d::Error naming the file and what is wrong: missing file, truncated data, unknown
// camera model, an image that names a missing camera, a track naming a missing image.
ColmapModel ReadColmapModel(const std::filesystem::path& folder);

enum class ColmapFormat { kBinary, kText };
// Writes cameras/images/points3D in the chosen format (through temporary files and renames).
void WriteColmapModel(const std::filesystem::path& folder,
                      const ColmapModel& model,
                      ColmapFormat format);

// The sparse model folder of a COLMAP workspace or HDR-GS scene: `root` itself when it holds
// cameras.bin/.txt, else root/sparse/0, else root/sparse; throws hdr4d::Error when none does.
std::filesystem::path FindColmapModelFolder(const std::filesystem::path& root);

}  // namespace hdr4d
