// Rendering a trained run (`hdr4d render`): the run's checkpoint and configuration give the
// model and the scene; each view of a split is rendered and written under its ground truth's
// file name, so `hdr4d eval OUT <scene>/<image folder>` compares them directly.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "method/gaussian_model.h"

namespace hdr4d::method {

struct RenderRunOptions {
  std::filesystem::path run;
  std::filesystem::path out;   // default: RUN/renders/<split>, RUN/renders/time, RUN/video
  std::string split = "test";  // train, test or val
  int threads = 0;
  // One view at any time: the camera of frame `camera_index` of the split, at `time`.
  std::optional<float> time;
  int camera_index = 0;
  // A camera path over time: `video_frames` frames orbiting the scene once while time runs
  // from 0 to 1, written as a PNG sequence and, when ffmpeg is installed, an MP4.
  int video_frames = 0;
  int fps = 24;
};

// Returns the number of images written.
int RenderRun(const RenderRunOptions& options);

// The orbit of the video: around the point the training cameras look at (least squares
// intersection of their optical axes), at their mean distance, about their mean up axis,
// starting at the first training camera. Frame k of n is at angle 2 pi k / n.
std::vector<Camera> OrbitCameras(const std::vector<Camera>& train_cameras, int frames);

// The model of a run's checkpoint (RUN/checkpoint.bin).
GaussianModel LoadRunModel(const std::filesystem::path& run);

}  // namespace hdr4d::method
