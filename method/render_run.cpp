#include "method/render_run.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdlib>
#include <numbers>

#include "core/dataset.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_util.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "method/checkpoint.h"
#include "method/render.h"

namespace hdr4d::method {
namespace fs = std::filesystem;

GaussianModel LoadRunModel(const fs::path& run) {
  return LoadCheckpoint(run / "checkpoint.bin").model;
}

namespace {

bool HaveFfmpeg() { return std::system("command -v ffmpeg >/dev/null 2>&1") == 0; }

}  // namespace

std::vector<Camera> OrbitCameras(const std::vector<Camera>& train, int frames) {
  HDR4D_CHECK(!train.empty() && frames > 0);
  // Least-squares point closest to every optical axis: sum (I - d d^T) p = sum (I - d d^T) c.
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  Eigen::Vector3d up = Eigen::Vector3d::Zero();
  for (const Camera& c : train) {
    const Eigen::Vector3d d =
        -c.world_from_cam_gl.block<3, 1>(0, 2).normalized();  // GL looks down -Z
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - d * d.transpose();
    a += p;
    b += p * c.Center();
    up += c.world_from_cam_gl.block<3, 1>(0, 1);
  }
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  if (std::abs(a.determinant()) > 1e-9) target = a.ldlt().solve(b);  // parallel axes: origin
  up = up.norm() > 1e-9 ? up.normalized() : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d start = train.front().Center() - target;
  std::vector<Camera> path;
  for (int k = 0; k < frames; ++k) {
    const double angle = 2 * std::numbers::pi * k / frames;
    const Eigen::Vector3d eye = target + Eigen::AngleAxisd(angle, up) * start;
    path.push_back(Camera{train.front().intrinsics, LookAtWorldFromCamGl(eye, target, up)});
  }
  return path;
}

int RenderRun(const RenderRunOptions& options) {
  const ThreadLimit limit(options.threads);
  const nlohmann::json config = ReadJsonFile(options.run / "config.json");
  if (!config.contains("data") || !config["data"].is_string()) {
    Fail("{}: key 'data' (the scene folder) missing", (options.run / "config.json").string());
  }
  const Split split = ParseSplit(options.split, "render");
  const Dataset dataset = LoadDataset(config["data"].get<std::string>(),
                                      {.image_check = ImageCheck::kNone, .require_test = false});
  const GaussianModel model = LoadRunModel(options.run);
  const fs::path out = options.out.empty() ? options.run / "renders" / options.split : options.out;
  RenderOptions render;
  render.sh_degree = model.basis.max_sh_degree;
  render.time_degree = model.temporal ? model.basis.max_time_degree : 0;
  render.background.assign(model.channels, config.value("background", 0.0f));
  const std::vector<Frame>& frames = dataset.FramesOf(split);
  if (frames.empty()) Fail("{}: the {} split has no frames", dataset.root.string(), options.split);
  FrameState state;
  std::vector<float> values;
  auto render_to = [&](const Camera& camera, float time, const fs::path& path) {
    const int w = camera.intrinsics.width, h = camera.intrinsics.height;
    values.resize(static_cast<std::size_t>(w) * h * model.channels);
    RenderForward(model, camera, time, render, &state, values.data());
    WriteImage(path, DisplayImageFromBuffer(values.data(), w, h, model.channels));
  };

  if (options.time) {
    if (options.camera_index < 0 || options.camera_index >= static_cast<int>(frames.size())) {
      Fail("render: --camera {} is not a frame of the {} split (0..{})", options.camera_index,
           options.split, frames.size() - 1);
    }
    if (!(*options.time >= 0 && *options.time <= 1))
      Fail("render: --time {} is outside [0, 1]", *options.time);
    const fs::path dir = options.out.empty() ? options.run / "renders" / "time" : options.out;
    const fs::path path = dir / fmt::format("{}_cam{:03d}_t{:.4f}.png", options.split,
                                            options.camera_index, *options.time);
    render_to(frames[options.camera_index].camera, *options.time, path);
    fmt::print("render: {}\n", path.string());
    return 1;
  }

  if (options.video_frames > 0) {
    std::vector<Camera> train_cameras;
    for (const Frame& f : dataset.train) train_cameras.push_back(f.camera);
    const std::vector<Camera> path = OrbitCameras(train_cameras, options.video_frames);
    const fs::path dir = options.out.empty() ? options.run / "video" : options.out;
    Progress progress("render video", options.video_frames);
    for (int k = 0; k < options.video_frames; ++k) {
      const float time =
          options.video_frames > 1 ? static_cast<float>(k) / (options.video_frames - 1) : 0.0f;
      render_to(path[k], time, dir / fmt::format("frame_{:04d}.png", k));
      progress.Advance();
    }
    progress.Finish();
    if (HaveFfmpeg()) {
      const fs::path mp4 = dir / "video.mp4";
      const std::string command = fmt::format(
          "ffmpeg -loglevel error -y -framerate {} -i '{}/frame_%04d.png' -vf "
          "'pad=ceil(iw/2)*2:ceil(ih/2)*2' -pix_fmt yuv420p -c:v libx264 '{}'",
          options.fps, dir.string(), mp4.string());
      if (std::system(command.c_str()) != 0)
        Fail("{}: ffmpeg failed to encode the frames in {}", mp4.string(), dir.string());
      fmt::print("render: {} frames and {}\n", options.video_frames, mp4.string());
    } else {
      fmt::print("render: {} frames in {} (install ffmpeg for an MP4)\n", options.video_frames,
                 dir.string());
    }
    return options.video_frames;
  }

  Progress progress("render", static_cast<std::int64_t>(frames.size()));
  for (const Frame& f : frames) {
    // Named like the ground truth so `hdr4d eval` pairs them.
    fs::path name = f.image_path.filename();
    if (name.extension() != ".png") name += ".png";
    render_to(f.camera, static_cast<float>(f.time), out / name);
    progress.Advance();
  }
  progress.Finish();
  return static_cast<int>(frames.size());
}

}  // namespace hdr4d::method
