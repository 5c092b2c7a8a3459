#include "datagen/dataset_assembly.h"

#include <fmt/format.h>

#include <fstream>

#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/util/parallel.h"
#include "core/geometry/ply.h"
#include "datagen/blender_render.h"

namespace hdr4d::datagen {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

Eigen::Matrix4d MatrixFromJson(const json& m) {
  Eigen::Matrix4d out;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) out(r, c) = m[r][c].get<double>();
  }
  return out;
}

}  // namespace

// Reads every EXR (a missing or corrupt one is an error naming the frame), checks its size, and
// writes it back as plain float RGB: Cycles stores its render and synchronisation times in the
// EXR header, which would make equal renders differ byte for byte. The pixels are unchanged.
// Returns the luminance histogram of all frames.
LuminanceHistogram NormaliseExrs(const ScenePreset& preset,
                                 const std::vector<PlannedRender>& renders,
                                 const fs::path& staging) {
  const int total = static_cast<int>(renders.size());
  std::vector<LuminanceHistogram> histograms(renders.size());
  ParallelFor(total, 1, [&](std::int64_t i) {
    const PlannedRender& r = renders[i];
    const fs::path path = staging / r.hdr_file;
    const auto frame = fmt::format("datagen: scene '{}': frame {}/{}", preset.scene, i + 1, total);
    if (!fs::exists(path)) {
      Fail("{}: Blender exited without writing {} (log: {})", frame, path.string(),
           (staging / kLogFile).string());
    }
    Image hdr;
    try {
      hdr = ReadImage(path);
    } catch (const Error& e) {
      Fail("{}: {}", frame, e.what());
    }
    if (hdr.width() != preset.width || hdr.height() != preset.height || hdr.channels() < 3) {
      Fail("{}: {}: {} pixels, expected {}x{}x3", frame, path.string(), hdr.ShapeString(),
           preset.width, preset.height);
    }
    hdr = hdr.Rgb();
    histograms[i].Add(hdr);
    WriteImage(path, hdr, {.format = PixelFormat::kFloat});
  });
  LuminanceHistogram all;
  for (const LuminanceHistogram& h : histograms) all.Merge(h);
  return all;
}

Dataset BuildDataset(const ScenePreset& preset,
                     const std::vector<PlannedRender>& renders,
                     const json& info,
                     const fs::path& staging) {
  Dataset dataset;
  dataset.root = staging;
  dataset.layout = "hdr4d";
  dataset.camera_angle_x = info["camera_angle_x"].get<double>();
  dataset.time_max_raw = 1.0;
  const PinholeIntrinsics intrinsics =
      PinholeIntrinsics::FromFovX(dataset.camera_angle_x, preset.width, preset.height);
  for (std::size_t i = 0; i < renders.size(); ++i) {
    const PlannedRender& r = renders[i];
    for (int k : r.exposure_indices) {
      Frame f;
      f.split = r.split;
      std::vector<Frame>& frames = r.split == Split::kTest ? dataset.test : dataset.train;
      f.index = static_cast<int>(frames.size());
      f.file_path = LdrFileName(r, k);
      f.image_path = staging / f.file_path;
      f.exr_file_path = r.hdr_file;
      f.hdr_path = staging / r.hdr_file;
      f.time_raw = f.time = r.time;
      f.exposure = preset.exposures[k];
      f.exposure_given = true;
      f.camera_id = r.camera_id;
      f.exposure_index = k;
      f.camera.intrinsics = intrinsics;
      f.camera.world_from_cam_gl = MatrixFromJson(info["renders"][i]["transform_matrix"]);
      frames.push_back(std::move(f));
    }
  }
  return dataset;
}

namespace {

// The sample times render_info.json reports (script version 2 on: 7 floats per point, x y z r g
// b t), or none (before: 6 floats per point, all at t = 0). A time outside (0, 1) is an error:
// the official loader would drop its points.
std::vector<double> ReportedPointTimes(const ScenePreset& preset, const json& info,
                                       const fs::path& info_file) {
  std::vector<double> times;
  if (!info.contains("points") || !info["points"].contains("times")) return times;
  const json& t = info["points"]["times"];
  bool ok = t.is_array() && !t.empty();
  for (std::size_t i = 0; ok && i < t.size(); ++i) {
    ok = t[i].is_number() && t[i].get<double>() > 0 && t[i].get<double>() < 1;
    if (ok) times.push_back(t[i].get<double>());
  }
  if (!ok) {
    Fail("datagen: scene '{}': {}: points.times must be a non-empty list of times inside (0, 1)",
         preset.scene, info_file.string());
  }
  return times;
}

}  // namespace

// point3d.ply from Blender's surface samples: float32 x y z r g b t per point, sampled at the
// plan's point_times (or x y z r g b at t = 0 from scripts before version 2).
std::int64_t WritePointCloud(const ScenePreset& preset, const json& info, const fs::path& staging) {
  const fs::path path = staging / kPointsFile;
  const std::vector<double> times = ReportedPointTimes(preset, info, staging / kInfoFile);
  const std::size_t stride = times.empty() ? 6 : 7;
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    Fail("datagen: scene '{}': {}: Blender exited without writing the surface points", preset.scene,
         path.string());
  }
  std::vector<float> values;
  float v;
  while (file.read(reinterpret_cast<char*>(&v), sizeof(v))) values.push_back(v);
  const std::int64_t expected = info.contains("points") ? info["points"].value("count", -1) : -1;
  if (values.size() % stride != 0 || static_cast<std::int64_t>(values.size() / stride) != expected) {
    Fail("datagen: scene '{}': {}: holds {} floats, expected {} per point for {} points",
         preset.scene, path.string(), values.size(), stride, expected);
  }
  PointCloud cloud;
  for (std::size_t i = 0; i < values.size(); i += stride) {
    cloud.positions.emplace_back(values[i], values[i + 1], values[i + 2]);
    cloud.colors.emplace_back(values[i + 3], values[i + 4], values[i + 5]);
    const float t = stride == 7 ? values[i + 6] : 0.0f;
    if (stride == 7 && !(t > 0 && t < 1)) {
      Fail("datagen: scene '{}': {}: point {} has time {}, outside (0, 1)", preset.scene,
           path.string(), i / stride, t);
    }
    cloud.times.push_back(t);
  }
  WritePly(staging / "point3d.ply", cloud);
  std::error_code ec;
  fs::remove(path, ec);  // an intermediate: point3d.ply holds the same points
  return static_cast<std::int64_t>(cloud.size());
}

}  // namespace hdr4d::datagen
