#include "method/run/render_split.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <future>
#include <iterator>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>
#include <tuple>

#include "core/files/atomic_file.h"
#include "core/dataset/dataset.h"
#include "core/dataset/dataset_checksum.h"
#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/files/json_util.h"
#include "core/files/made_folders.h"
#include "core/files/output_guard.h"
#include "core/util/child_process.h"
#include "core/util/parallel.h"
#include "method/gaussian/sh4d.h"
#include "core/util/progress.h"
#include "method/optim/permute_rows.h"
#include "method/optim/time_order.h"
#include "method/render/frame_render.h"
#include "method/render/learned_background.h"
#include "method/render/view_renderer.h"
#include "method/tonemap/camera_correction.h"
#include "method/tonemap/radiance_bank.h"
#include "method/tonemap/tone_mapper_registry.h"
#include "method/train/checkpoint.h"
#include "method/train/hdr_head_fit.h"  // ReadHdrHead
#include "method/train/resume_check.h"  // RequireCheckpointOfThisConfig
#include "method/train/run_folder.h"    // kDataRecordName
#include "method/train/train_views.h"   // DownscaledIntrinsics

namespace hdr4d::method {
namespace fs = std::filesystem;

namespace {

// A run shows the views it was trained on: the scene's frames and its JSON files (cameras, times,
// exposures) as RUN/data_checksums.json records them (runs from before the record: unchecked).
void RequireCamerasOfTheRun(const fs::path& run, const Dataset& dataset) {
  const fs::path file = run / kDataRecordName;
  std::error_code ec;
  if (!fs::exists(file, ec)) return;
  const DatasetRecord before = DatasetRecord::FromJson(ReadJsonFile(file), file.string());
  if (const std::string change = DescribeCameraChange(before, dataset); !change.empty()) {
    Fail("{}: the scene changed since run {} was trained ({} records it): {}; its views are "
         "shown on the cameras it was trained with (put the scene back, or train a new run on it)",
         dataset.root.string(), run.string(), file.string(), change);
  }
}

// The run's scene, named by config.json's `data`: there, and with the cameras it was trained on.
Dataset LoadRunScene(const fs::path& run, const nlohmann::json& json, const JsonField& config) {
  if (json.is_object() && json.contains("hexplane"))
    Fail("{}: a HexPlane run (a grid, not Gaussians): `hdr4d render` renders it; export-ply, "
         "view and tone-curves read runs of Gaussians", run.string());
  const std::string data = config["data"].String();
  std::error_code ec;
  if (!fs::is_directory(data, ec))
    config["data"].Fail(fmt::format("the scene {} is not there (moved or deleted since the run "
                                    "was trained?): put it back, or set the key to where it is",
                                    data));
  Dataset dataset = LoadDataset(
      data, {.image_check = ImageCheck::kNone,
             .exposure_unit = RecordedExposureUnit(json, (run / "config.json").string()),
             .require_test = false});
  RequireCamerasOfTheRun(run, dataset);
  return dataset;
}

// --camera-correction runs: the tone mapper wrapped in the learned gains, and each frame's row.
// The camera count the run recorded must be the dataset's (the data checks guard the images;
// this guards the frames' cameras).
void WrapCameraCorrection(const JsonField& config, const nlohmann::json& trainer,
                          const std::string& checkpoint, LoadedRun* r) {
  if (!r->tone_mapper) config["camera_correction"].Fail("the run has no tone mapper to correct");
  r->correction_cameras = FindCorrectionCameras(r->dataset);
  const int recorded = static_cast<int>(config["camera_correction_cameras"].Int(1, 1 << 20));
  if (recorded != r->correction_cameras.count) {
    config["camera_correction_cameras"].Fail(
        fmt::format("the run learned gains for {} cameras, and the dataset's training split has "
                    "{} now",
                    recorded, r->correction_cameras.count));
  }
  auto wrapper = std::make_unique<CameraCorrectedToneMapper>(
      std::move(r->tone_mapper), recorded, CameraCorrectionOptions{});
  wrapper->FromJson(trainer, checkpoint);
  r->tone_mapper = std::move(wrapper);
}

}  // namespace

LoadedRun LoadRun(const fs::path& run, int resolution_override) {
  LoadedRun r;
  const fs::path config_path = run / "config.json";
  r.config = ReadJsonFile(config_path);
  // Typed reads name the file and the key of a value that is missing or of the wrong type.
  const JsonField config(r.config, config_path.string());
  r.dataset = LoadRunScene(run, r.config, config);
  // A run trained at --resolution R renders every split at it (runs from before: 1), unless
  // the caller asks for another.
  const int run_resolution = static_cast<int>(config.IntOr("resolution", 1, 1, 1 << 16));
  if (resolution_override < 0 || resolution_override > (1 << 16))
    Fail("{}: resolution {} must be within [1, 65536] (0: the run's own)", run.string(),
         resolution_override);
  const int resolution = resolution_override > 0 ? resolution_override : run_resolution;
  for (std::vector<Frame>* frames : {&r.dataset.train, &r.dataset.test, &r.dataset.val}) {
    for (Frame& f : *frames) {
      const PinholeIntrinsics& k = f.camera.intrinsics;
      if (std::string p = ResolutionProblem(k.width, k.height, resolution); !p.empty()) {
        if (resolution_override > 0) Fail("{}: {}", f.image_path.string(), p);
        config["resolution"].Fail(fmt::format("{}: {}", f.image_path.string(), p));
      }
      f.camera.intrinsics = DownscaledIntrinsics(k, resolution);
    }
  }
  const fs::path checkpoint_path = run / "checkpoint.bin";
  Checkpoint c = LoadCheckpoint(checkpoint_path, {.optimizer_state = false});  // looked at only
  r.model = std::move(c.model);
  r.hdr_head = ReadHdrHead(c, r.model.size(), checkpoint_path.string());
  r.background = static_cast<float>(config.NumberOr("background", 0.0));
  if (!(r.background >= 0 && r.background <= 1))
    config["background"].Fail(fmt::format("must be within [0, 1], got {}", r.background));
  r.num_times = static_cast<int>(config.IntOr("num_times", 1, 1, 10'000'000));
  if (config.Has("learn_background") && config["learn_background"].Bool()) {
    r.learned_background = ReadLearnedBackground(c.trainer, LearnedBackgroundChannels(r.model),
                                                 checkpoint_path.string());
  }
  // Last, after the typed reads, which name a bad value more precisely: what they cannot see, a
  // config.json that is not the one the checkpoint was trained with.
  const auto trained_with = [&] {
    RequireCheckpointOfThisConfig(c.trainer, r.config, config_path, checkpoint_path);
  };
  if (!config.Has("resolved")) {  // runs of plain 4DGS from before HDR training existed
    r.resolved.hdr_colors = r.model.color_mode == ColorMode::kLogHdr;
    trained_with();
    return r;
  }
  const JsonField resolved = config["resolved"].Object();
  r.resolved.hdr_colors = resolved["hdr_colors"].Bool();
  // Also for runs whose checkpoint holds no record of their configuration.
  if (r.resolved.hdr_colors != (r.model.color_mode == ColorMode::kLogHdr))
    resolved["hdr_colors"].Fail(fmt::format("is {}, but {} holds {} colours", r.resolved.hdr_colors,
                                            checkpoint_path.string(),
                                            r.resolved.hdr_colors ? "LDR" : "log-HDR"));
  r.resolved.ldr_gaussian = resolved["ldr_gaussian"].Bool();
  r.resolved.ldr_pixel = resolved["ldr_pixel"].Bool();
  r.resolved.hdr = resolved["hdr"].Bool();
  r.resolved.final_ldr_from_pixels = resolved["final_ldr_from_pixels"].Bool();
  // Runs from before the key trained with the reference's floor.
  r.resolved.pixel_log_epsilon = resolved.Has("pixel_log_epsilon")
                                     ? static_cast<float>(resolved["pixel_log_epsilon"].Number())
                                     : kReferencePixelLogEpsilon;
  if (r.config.contains("tone_mapper")) {
    r.tone_mapper =
        MakeToneMapper(ToneMapperConfig::FromJson(r.config["tone_mapper"], config_path.string()));
    if (c.tone_mapper_state.empty())
      Fail("{}: checkpoint has no tone mapper state", checkpoint_path.string());
    std::istringstream state(c.tone_mapper_state);
    r.tone_mapper->Load(state, checkpoint_path.string());
  }
  if (config.Has("camera_correction") && config["camera_correction"].Bool())
    WrapCameraCorrection(config, c.trainer, checkpoint_path.string(), &r);
  trained_with();
  return r;
}

std::string LoadedRun::MethodName() const {
  const auto hdr = config.find("hdr");
  if (hdr == config.end() || !hdr->is_object()) return "?";
  const auto method = hdr->find("method");
  return method != hdr->end() && method->is_string() ? method->get<std::string>() : "?";
}

void ProtectRunInputs(const fs::path& run, const fs::path& own_output) {
  const std::string role = fmt::format("a file of run {} that this command reads", run.string());
  for (const char* name : kRunFolderFiles) ProtectInputFile(run / name, role);
  // Renders are what `hdr4d eval` scores: no other output may land among them. The folder this
  // command renders into (and what lies below it) is its own to rewrite.
  std::error_code ec;
  const fs::path renders = run / "renders";
  if (!fs::is_directory(renders, ec)) return;
  const fs::path own_resolved = own_output.empty() ? fs::path() : fs::weakly_canonical(own_output, ec);
  const auto own = [&](const fs::path& folder) {  // own_output or below it
    if (own_resolved.empty()) return false;
    std::error_code resolve_ec;
    const fs::path rel = fs::weakly_canonical(folder, resolve_ec).lexically_relative(own_resolved);
    return !rel.empty() && *rel.begin() != "..";
  };
  const std::string renders_role = fmt::format("the renders of run {} (inputs of eval)", run.string());
  if (!own(renders)) ProtectInputFolder(renders, renders_role);
  for (fs::recursive_directory_iterator it(renders, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code type_ec;
    if (it->is_directory(type_ec) && !it->is_symlink(type_ec) && !own(it->path()))
      ProtectInputFolder(it->path(), renders_role);
  }
}

fs::path RenderOutputFolder(const RenderRunOptions& options) {
  if (!options.out.empty()) return options.out;
  if (options.time) return options.run / "renders" / "time";
  if (options.video_frames > 0) return options.run / "video";
  return options.run / "renders" / options.split;
}

double MedianExposure(const Dataset& dataset) {
  std::vector<double> e;
  for (const Frame& f : dataset.train) e.push_back(f.exposure);
  if (e.empty()) return 1.0;
  std::nth_element(e.begin(), e.begin() + e.size() / 2, e.end());
  return e[e.size() / 2];
}

namespace {

bool HaveFfmpeg() { return std::system("command -v ffmpeg >/dev/null 2>&1") == 0; }

// `text` as literal text inside an ffmpeg image-sequence pattern: its own '%' doubled (a folder
// named 'V%02d' would otherwise be read as a frame number, issue 51 §24).
std::string FfmpegPatternLiteral(const std::string& text) {
  std::string literal;
  for (char c : text) literal += c == '%' ? std::string("%%") : std::string(1, c);
  return literal;
}

}  // namespace

void OrderForRendering(LoadedRun* run) {
  GaussianModel& model = run->model;
  if (!model.temporal || model.size() < 2) return;
  // The dataset's time range (every split: a render may show any of them), else [0, 1].
  float time_min = 0.0f, time_max = 1.0f;
  bool any = false;
  for (const std::vector<Frame>* frames :
       {&run->dataset.train, &run->dataset.test, &run->dataset.val}) {
    for (const Frame& f : *frames) {
      const auto t = static_cast<float>(f.time);
      if (!std::isfinite(t)) continue;
      time_min = any ? std::min(time_min, t) : t;
      time_max = any ? std::max(time_max, t) : t;
      any = true;
    }
  }
  ReorderRun(VisibleTimeOrder(model, time_min, time_max), run);
}

void ReorderRun(const std::vector<std::uint32_t>& order, LoadedRun* run) {
  ReorderGaussians(order, &run->model, nullptr, nullptr);
  // The HDR head's offsets are rows of the model's order too.
  if (!run->hdr_head.offset.empty()) PermuteRowsInPlace(run->hdr_head.offset.data(), 3, order);
}

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
  // Cameras that share one centre (a fixed camera, a tripod) have no orbit about what they look
  // at: the video keeps the first camera while time runs (LookAt from a point to itself aborted).
  if (!(start.norm() > 1e-9 * std::max(1.0, target.norm())))
    return std::vector<Camera>(frames, train.front());
  for (int k = 0; k < frames; ++k) {
    const double angle = 2 * std::numbers::pi * k / frames;
    const Eigen::Vector3d eye = target + Eigen::AngleAxisd(angle, up) * start;
    path.push_back(Camera{train.front().intrinsics, LookAtWorldFromCamGl(eye, target, up)});
  }
  return path;
}

std::unique_ptr<ViewRenderer> MakeRunRenderer(const LoadedRun& run) {
  RenderOptions render;
  // Bands that stayed frozen in training (zero) are skipped: the same image, less work.
  std::tie(render.sh_degree, render.time_degree) = UsedColorDegrees(run.model);
  if (!run.model.temporal) render.time_degree = 0;
  return std::make_unique<ViewRenderer>(
      run.model, run.tone_mapper.get(), run.resolved, render, run.background,
      run.learned_background ? &*run.learned_background : nullptr, &run.hdr_head);
}

ToneFrame RunToneFrame(const LoadedRun& run, float time, double exposure, int camera_index) {
  return {RadianceBank::TimeIndex(time, run.num_times), -1, static_cast<float>(std::log(exposure)),
          camera_index};
}

namespace {

// The CLI checks its flags too; a library caller gets the same refusals.
void CheckRenderOptions(const RenderRunOptions& options) {
  if (options.threads < 0) Fail("render: threads {} must be >= 0", options.threads);
  if (options.video_frames < 0) Fail("render: video frames {} must be >= 1", options.video_frames);
  if (options.fps < 1 || options.fps > 1000)
    Fail("render: fps {} must be within [1, 1000]", options.fps);
  if (options.png_compression < 0 || options.png_compression > 9)
    Fail("render: PNG compression {} must be within [0, 9]", options.png_compression);
  if (options.camera_index < 0) Fail("render: camera {} must be >= 0", options.camera_index);
  if (options.exposure && !(*options.exposure > 0 && std::isfinite(*options.exposure)))
    Fail("render: --exposure {} must be a positive number of seconds", *options.exposure);
  if (!options.timing.empty() && (options.time || options.video_frames > 0))
    Fail("render: --timing times the views of a split render; it does not apply to {}",
         options.time ? "--time" : "--video");
  if (!options.timing.empty()) CheckOutput(options.timing);  // before the renders, not after
}

// Renders views and writes their files. A command's renders are moved into place together once
// all are made (Commit): a failure or a kill halfway never leaves new renders mixed with an
// earlier run's (core/files/atomic_file.h). A view's files are written on another thread while
// the next view renders (writing took several times the render: docs/history/render-speed.md), one
// view at a time; not with one thread, nor with --timing, whose render times must not share the
// cores with a writer.
class ViewFileWriter {
 public:
  ViewFileWriter(const LoadedRun& run, ViewRenderer* renderer, const RenderRunOptions& options)
      : run_(run),
        renderer_(*renderer),
        options_(options),
        overlap_writes_(MaxThreads() > 1 && options.timing.empty()) {}

  // Renders one view; writes the LDR image to ldr_path and the HDR one to hdr_path (each when
  // the model has that output and the path is not empty). Returns the number of files written.
  // camera_index: the view's row of the run's camera correction (-1: none).
  int Render(const Camera& camera,
             float time,
             double exposure,
             const fs::path& ldr_path,
             const fs::path& hdr_path,
             int camera_index = -1) {
    const int w = camera.intrinsics.width, h = camera.intrinsics.height;
    const ToneFrame frame = RunToneFrame(run_, time, exposure, camera_index);
    const auto start = std::chrono::steady_clock::now();
    // No HDR file to write (--no-hdr, video frames): the HDR channels are not blended.
    renderer_.Render(camera, time, frame, &ldr_,
                     options_.write_hdr && !hdr_path.empty() ? &hdr_ : nullptr);
    render_seconds_.push_back(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    // Copies: the renderer reuses its buffers for the next view.
    std::optional<Image> ldr_image, hdr_image;
    if (!ldr_.empty() && !ldr_path.empty())
      ldr_image = DisplayImageFromBuffer(ldr_.data(), w, h, 3);
    if (options_.write_hdr && !hdr_.empty() && !hdr_path.empty()) {
      hdr_image.emplace(w, h, 3, Encoding::kLinear);
      std::copy(hdr_.begin(), hdr_.end(), hdr_image->data());
    }
    const int written = (ldr_image ? 1 : 0) + (hdr_image ? 1 : 0);
    auto write = [this, ldr_path, hdr_path, ldr_image = std::move(ldr_image),
                  hdr_image = std::move(hdr_image)] {
      if (ldr_image) {
        WriteImage(ldr_path, *ldr_image,
                   {.png_compression = options_.png_compression, .batch = &batch_});
      }
      // Float, not half: radiance in physical units passes half's 65504 (the stress suite's
      // 1e6 scene) and falls below its normal range (1e-6).
      if (hdr_image)
        WriteImage(hdr_path, *hdr_image, {.format = PixelFormat::kFloat, .batch = &batch_});
    };
    FinishWriting();  // the previous view's
    if (overlap_writes_) {
      writing_ = std::async(std::launch::async, std::move(write));
    } else {
      write();
    }
    return written;
  }

  // Moves every file written so far into place.
  void Commit() {
    FinishWriting();
    batch_.Commit();
  }

  // Per view, the Render call alone (seconds).
  const std::vector<double>& render_seconds() const { return render_seconds_; }

 private:
  void FinishWriting() {
    if (writing_.valid()) writing_.get();  // rethrows the writer's error
  }

  const LoadedRun& run_;
  ViewRenderer& renderer_;
  const RenderRunOptions& options_;
  const bool overlap_writes_;
  std::vector<float> ldr_, hdr_;
  std::vector<double> render_seconds_;
  FileBatch batch_;
  // Declared after the batch: an unfinished write ends before the batch drops its files.
  std::future<void> writing_;
};

// --time: one view, the camera of frame options.camera_index at options.time.
int RenderAtTime(const RenderRunOptions& options,
                 const std::vector<Frame>& frames,
                 const std::vector<int>& camera_rows,
                 ViewFileWriter* writer) {
  if (options.camera_index < 0 || options.camera_index >= static_cast<int>(frames.size())) {
    Fail("render: --camera {} is not a frame of the {} split (0..{})", options.camera_index,
         options.split, frames.size() - 1);
  }
  if (!(*options.time >= 0 && *options.time <= 1))
    Fail("render: --time {} is outside [0, 1]", *options.time);
  const fs::path dir = RenderOutputFolder(options);
  CheckOutputFolder(dir);
  const std::string stem =
      fmt::format("{}_cam{:03d}_t{:.4f}", options.split, options.camera_index, *options.time);
  const Frame& f = frames[options.camera_index];
  const int written = writer->Render(f.camera, *options.time, options.exposure.value_or(f.exposure),
                                     dir / (stem + ".png"), dir / (stem + ".exr"),
                                     camera_rows.empty() ? -1 : camera_rows[options.camera_index]);
  writer->Commit();
  fmt::print("render: {} ({} file{})\n", (dir / stem).string(), written, written == 1 ? "" : "s");
  return written;
}

// Encodes the video's PNG frames in `dir` as dir/video.mp4, through the atomic writer like every
// output (a killed ffmpeg leaves no half video); -frames:v: exactly this video's frames, even if
// a longer earlier one left more.
// ffmpeg is a child that dies with hdr4d and is stopped by a stop signal before the temporary
// MP4 is removed (core/util/child_process.h); its messages go to a private log, quoted on failure.
fs::path EncodeVideo(const fs::path& dir, int frames, int fps) {
  const fs::path mp4 = dir / "video.mp4";
  const fs::path logs = MakePrivateTempFolder("hdr4d-ffmpeg-");
  const auto remove_logs = [&] {
    std::error_code ec;
    fs::remove_all(logs, ec);
  };
  try {
    WriteFileAtomicAt(mp4, [&](const fs::path& tmp) {
      const std::vector<std::string> argv = {
          "ffmpeg", "-nostdin", "-loglevel", "error", "-y", "-framerate", std::to_string(fps),
          "-i", FfmpegPatternLiteral(dir.string()) + "/frame_%04d.png", "-frames:v",
          std::to_string(frames), "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-pix_fmt", "yuv420p",
          "-c:v", "libx264", "-f", "mp4", tmp.string()};
      if (const int code = RunLoggedChild(argv, {}, logs / "ffmpeg.log"); code != 0)
        Fail("{}: ffmpeg failed to encode the frames in {} (exit {}): {}", mp4.string(),
             dir.string(), code, LastLogLine(logs / "ffmpeg.log"));
    });
  } catch (...) {
    remove_logs();
    throw;
  }
  remove_logs();
  return mp4;
}

// --video: the orbit (OrbitCameras) as PNG frames and, with ffmpeg, an MP4.
int RenderVideo(const RenderRunOptions& options,
                const LoadedRun& run,
                const ViewRenderer& renderer,
                ViewFileWriter* writer) {
  if (!renderer.has_ldr()) {
    Fail("render: --video writes LDR frames, and this run ({}) has no LDR output",
         run.MethodName());
  }
  const double exposure = options.exposure.value_or(MedianExposure(run.dataset));
  std::vector<Camera> train_cameras;
  for (const Frame& f : run.dataset.train) train_cameras.push_back(f.camera);
  const std::vector<Camera> path = OrbitCameras(train_cameras, options.video_frames);
  const fs::path dir = RenderOutputFolder(options);
  CheckOutputFolder(dir);
  Progress progress("render video", options.video_frames);
  for (int k = 0; k < options.video_frames; ++k) {
    const float time =
        options.video_frames > 1 ? static_cast<float>(k) / (options.video_frames - 1) : 0.0f;
    writer->Render(path[k], time, exposure, dir / fmt::format("frame_{:04d}.png", k), {});
    progress.Advance();
  }
  progress.Finish();
  writer->Commit();
  FinishVideo(dir, options.video_frames, options.fps);
  return options.video_frames;
}

// --timing: each view's render time and the frames per second over every view but the first
// (the warm-up; with one view, that view).
void WriteRenderTiming(const fs::path& path, const std::vector<double>& render_seconds) {
  const std::size_t warmup = render_seconds.size() > 1 ? 1 : 0;
  double timed = 0;
  for (std::size_t i = warmup; i < render_seconds.size(); ++i) timed += render_seconds[i];
  const double fps = timed > 0 ? static_cast<double>(render_seconds.size() - warmup) / timed : 0.0;
  WriteJsonFile(path, {{"views", render_seconds.size()},
                       {"warmup_views", warmup},
                       {"threads", MaxThreads()},
                       {"fps", FiniteOrNull(fps)},
                       {"view_seconds", render_seconds}});
}

// Where a frame's render goes inside the output folder: its file's path below the dataset's
// image folder (the path from the dataset's root without its first folder), so frames in
// sub-folders (`images/cam0/x.png`, calibrate's layout) keep them and never overwrite each other
// (issue 51 §4); a flat `images/x.png` stays `x.png`. A path that leaves the root keeps its name.
fs::path RenderRelativePath(const fs::path& file, const fs::path& root) {
  const fs::path rel = file.lexically_normal().lexically_relative(root.lexically_normal());
  if (rel.empty() || *rel.begin() == ".." || rel.is_absolute()) return file.filename();
  fs::path below;
  for (auto it = std::next(rel.begin()); it != rel.end(); ++it) below /= *it;
  return below.empty() ? rel : below;
}

// The LDR and HDR output paths of a frame, relative to the output folder.
std::pair<fs::path, fs::path> RenderNames(const Frame& f, const fs::path& root) {
  fs::path name = RenderRelativePath(f.image_path, root);
  if (name.extension() != ".png") name += ".png";
  fs::path hdr_name = f.hdr_path ? RenderRelativePath(*f.hdr_path, root)
                                 : RenderRelativePath(f.image_path, root).replace_extension();
  if (hdr_name.extension() != ".exr") hdr_name += ".exr";
  return {name, hdr_name};
}

// Every view of the split, named like its ground truth (RenderNames); two frames that would
// write one file are refused before any render.
// camera_rows: each frame's row of the run's camera correction (empty: none).
int RenderSplitViews(const RenderRunOptions& options,
                     const Dataset& dataset,
                     const std::vector<Frame>& frames,
                     const std::vector<int>& camera_rows,
                     ViewFileWriter* writer) {
  const fs::path out = RenderOutputFolder(options);
  CheckOutputFolder(out);  // before the first render: never among the dataset's images
  // Output name -> the truth it stands for (the exposures of one view share their HDR render).
  std::map<fs::path, std::pair<fs::path, const Frame*>> taken;
  for (const Frame& f : frames) {
    const auto [name, hdr_name] = RenderNames(f, dataset.root);
    const fs::path hdr_truth = f.hdr_path ? *f.hdr_path : fs::path(f.image_path).replace_extension();
    for (const auto& [n, truth] : {std::pair{name, f.image_path}, std::pair{hdr_name, hdr_truth}}) {
      const auto [it, added] = taken.emplace(n, std::pair{truth, &f});
      if (!added && it->second.first != truth) {
        Fail("render: frames {} and {} of the {} split would both be rendered to {}: their "
             "file names collide",
             it->second.second->index, f.index, options.split, (out / n).string());
      }
    }
  }
  Progress progress("render", static_cast<std::int64_t>(frames.size()));
  int written = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const Frame& f = frames[i];
    const auto [name, hdr_name] = RenderNames(f, dataset.root);
    written += writer->Render(f.camera, static_cast<float>(f.time),
                              options.exposure.value_or(f.exposure), out / name, out / hdr_name,
                              camera_rows.empty() ? -1 : camera_rows[i]);
    progress.Advance();
  }
  progress.Finish();
  writer->Commit();
  if (!options.timing.empty()) WriteRenderTiming(options.timing, writer->render_seconds());
  return written;
}

}  // namespace

void FinishVideo(const fs::path& dir, int frames, int fps) {
  if (HaveFfmpeg()) {
    const fs::path mp4 = EncodeVideo(dir, frames, fps);
    fmt::print("render: {} frames and {}\n", frames, mp4.string());
  } else {
    fmt::print("render: {} frames in {} (install ffmpeg for an MP4)\n", frames, dir.string());
  }
}

int RenderRun(const RenderRunOptions& options) {
  CheckRenderOptions(options);
  const ThreadLimit limit(options.threads);
  const Split split = ParseSplit(options.split, "render");
  // A failed render takes away the output folders it made (when nothing but folders is there).
  const fs::path made = FirstMissingFolder(RenderOutputFolder(options));
  try {
    LoadedRun run = LoadRun(options.run, options.resolution);
    OrderForRendering(&run);
    const std::unique_ptr<ViewRenderer> renderer = MakeRunRenderer(run);
    const std::vector<Frame>& frames = run.dataset.FramesOf(split);
    if (frames.empty())
      Fail("{}: the {} split has no frames", run.dataset.root.string(), options.split);
    ViewFileWriter writer(run, renderer.get(), options);
    if (options.time)
      return RenderAtTime(options, frames, run.correction_cameras.Of(split), &writer);
    if (options.video_frames > 0) return RenderVideo(options, run, *renderer, &writer);
    return RenderSplitViews(options, run.dataset, frames, run.correction_cameras.Of(split),
                            &writer);
  } catch (...) {
    RemoveIfEmptyTree(made);
    throw;
  }
}

}  // namespace hdr4d::method
