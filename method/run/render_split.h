// Rendering a trained run (`hdr4d render`): the run's checkpoint and configuration give the
// model, its tone mapper and the scene; each view of a split is rendered and written under its
// ground truth's file names (the LDR render as its file_path, the HDR render as its
// exr_file_path), so `hdr4d eval OUT <scene>/<image folder>` compares them directly.
#pragma once

#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/camera.h"
#include "core/dataset/dataset.h"
#include "method/gaussian/gaussian_model.h"
#include "method/render/hdr_head.h"
#include "method/render/resolved_hdr_training.h"
#include "method/render/view_renderer.h"
#include "method/train/correction_cameras.h"
#include "method/tonemap/tone_mapper.h"

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
  // LDR renders at this exposure (seconds) instead of each frame's own (--time and the video
  // default to the median training exposure).
  std::optional<double> exposure;
  bool write_hdr = true;  // also the linear HDR render as EXR, for models with HDR colours
  // Split renders only: when set, a JSON file with each view's render time (slicing, tone
  // mapping, rasterisation; not the file writes) and the frames per second over every view but
  // the first (the warm-up; with one view, that view).
  std::filesystem::path timing;
  // Render at this reduction of the scene's images instead of the run's own (0): a run trained
  // at --resolution 2 renders its full-size views with 1. The same check as training: each
  // image's size must be divisible by it.
  int resolution = 0;
  // zlib level of the LDR PNGs: 1 writes an 800x800 render ~3x faster than the usual 6, which
  // took ~4x the render itself (docs/history/render-speed.md); renders are remade at will, so speed
  // wins over 30-45% of file size.
  int png_compression = 1;
};

// Returns the number of images written.
int RenderRun(const RenderRunOptions& options);

// The orbit of the video: around the point the training cameras look at (least squares
// intersection of their optical axes), at their mean distance, about their mean up axis,
// starting at the first training camera. Frame k of n is at angle 2 pi k / n. Cameras that share
// one centre have no orbit: every frame is the first training camera (time still runs).
std::vector<Camera> OrbitCameras(const std::vector<Camera>& train_cameras, int frames);

// A video's frames DIR/frame_%04d.png (0 .. frames - 1) encoded as DIR/video.mp4 when ffmpeg is
// installed (through the atomic writer); says which on stdout.
void FinishVideo(const std::filesystem::path& dir, int frames, int fps);

// Everything a trained run needs to render: its configuration, scene, model and tone mapper.
struct LoadedRun {
  nlohmann::json config;
  Dataset dataset;
  GaussianModel model;
  std::unique_ptr<ToneMapper> tone_mapper;  // null for methods without one
  ResolvedHdrTraining resolved;
  int num_times = 1;
  float background = 0;
  std::optional<std::vector<float>> learned_background;  // runs trained with --learn-background
  HdrHead hdr_head;                                        // runs trained with --hdr-head
  // Runs trained with --camera-correction: tone_mapper is the correction's wrapper, and each
  // frame's camera row (RunToneFrame); count 0 otherwise.
  CorrectionCameras correction_cameras;
  // The method's name from the configuration, or "?" (for messages).
  std::string MethodName() const;
};
// The median training exposure: a middle exposure of the bracket for views that have none.
double MedianExposure(const Dataset& dataset);

// Throws hdr4d::Error naming the file when the run is incomplete or inconsistent.
// The run's tone mapper is rebuilt by kind (tone_mapper_registry.h): a baseline's kind needs
// baselines::RegisterToneMappers() first.
// resolution: 0 renders at the run's own (config.json "resolution"), R > 0 at R instead.
LoadedRun LoadRun(const std::filesystem::path& run, int resolution = 0);

// Puts a 4D model's Gaussians (and its HDR head's rows) in the order their time windows open
// over the dataset's time range (method/optim/time_order.h), as the trainer keeps them: a frame's
// Gaussians then sit together in memory. The trainer sorts at each densification only (and runs
// from before it never), while the windows keep moving until the end; sorted on load, runs
// saved before the trainer sorted rendered 2.6% (r800, 4 times) and 16% (the paper scene)
// faster (docs/history/real-run-speed.md, twentieth pass). The images change only where Gaussians
// sit at exactly equal depth, which then blend in another order. Static models are left as
// they are.
void OrderForRendering(LoadedRun* run);
// Moves Gaussian order[k] to row k in the run's model and its HDR head's offsets (`order` a
// permutation of the model's rows, checked).
void ReorderRun(const std::vector<std::uint32_t>& order, LoadedRun* run);

// The renderer `hdr4d render` draws a loaded run's views with (the run must outlive it), and the
// tone-mapper frame of a view at `time` (in [0, 1]) with `exposure` seconds, by the training
// camera `camera_index` (a row of run.correction_cameras; -1: any other camera, uncorrected).
std::unique_ptr<ViewRenderer> MakeRunRenderer(const LoadedRun& run);
ToneFrame RunToneFrame(const LoadedRun& run, float time, double exposure, int camera_index = -1);

// For commands that only read a run (render, export-ply, tone-curves): its files (kRunFolderFiles)
// and its renders (every folder under RUN/renders but `own_output`, the folder the command itself
// renders into, and those below it) become protected inputs (core/files/output_guard.h), so no
// output of theirs replaces them.
void ProtectRunInputs(const std::filesystem::path& run,
                      const std::filesystem::path& own_output = {});

// Where `hdr4d render` writes: --out, else RUN/renders/time (--time), RUN/video (--video) or
// RUN/renders/<split>.
std::filesystem::path RenderOutputFolder(const RenderRunOptions& options);

}  // namespace hdr4d::method
