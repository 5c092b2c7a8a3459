// A HexPlane run folder: config.json (the method, scene, resolution and the HexPlane settings),
// checkpoint.bin (HexPlaneModel::Save) and results.json, like the Gaussian runs'; read back
// here for `hdr4d render` (split views, one view at any time, an orbit video).
#include <fmt/format.h>

#include <chrono>
#include <set>

#include "baselines/hexplane/hexplane_render.h"
#include "baselines/hexplane/hexplane_run.h"
#include "baselines/hexplane/heap_policy.h"
#include "core/dataset/dataset.h"
#include "core/files/atomic_file.h"
#include "core/files/json_util.h"
#include "core/files/output_guard.h"
#include "core/image/image_io.h"
#include "core/util/error.h"
#include "core/util/parallel.h"
#include "core/util/progress.h"
#include "method/run/render_split.h"

namespace hdr4d::baselines::hexplane {
namespace fs = std::filesystem;

bool IsHexPlaneRun(const fs::path& run) {
  const fs::path config = run / "config.json";
  if (!fs::exists(config)) return false;
  const nlohmann::json j = ReadJsonFile(config);
  return j.is_object() && j.contains("hexplane");
}

std::optional<std::string> HexPlaneMethodOfRun(const fs::path& run) {
  if (!IsHexPlaneRun(run)) return std::nullopt;
  const nlohmann::json j = ReadJsonFile(run / "config.json");
  const std::string method = j.value("method", std::string());
  if (!IsHexPlaneMethod(method)) return std::nullopt;
  return method;
}

LoadedHexPlaneRun LoadHexPlaneRun(const fs::path& run, int resolution_override) {
  LoadedHexPlaneRun r;
  const fs::path config_path = run / "config.json";
  const nlohmann::json j = ReadJsonFile(config_path);
  const JsonField config(j, config_path.string());
  r.config = HexPlaneConfig::FromJson(j["hexplane"], config_path.string());
  r.resolution = resolution_override > 0
                     ? resolution_override
                     : static_cast<int>(config.IntOr("resolution", 1, 1, 1 << 16));
  r.dataset = LoadDataset(config["data"].String(),
                          {.image_check = ImageCheck::kNone,
                           .exposure_unit = RecordedExposureUnit(j, config_path.string()),
                           .require_test = false});
  r.model = HexPlaneModel::Load(run / "checkpoint.bin", r.config);
  return r;
}

namespace {

// Stages a view's images: the LDR PNG (where the model has an LDR output) and the HDR EXR
// (when `exr` is not empty and the model has HDR colours). Returns the files written.
int WriteImages(const std::vector<float>& ldr, const std::vector<float>& hdr, int w, int h,
                const fs::path& png, const fs::path& exr, int png_compression, FileBatch* batch) {
  int written = 0;
  if (!ldr.empty()) {
    WriteImage(png, DisplayImageFromBuffer(ldr.data(), w, h, 3),
               {.png_compression = png_compression, .batch = batch});
    ++written;
  }
  if (!hdr.empty() && !exr.empty()) {
    Image image(w, h, 3, Encoding::kLinear);
    std::copy(hdr.begin(), hdr.end(), image.data());
    WriteImage(exr, image, {.format = PixelFormat::kFloat, .batch = batch});
    ++written;
  }
  return written;
}

// Renders one view and stages its images (WriteImages).
int WriteView(const LoadedHexPlaneRun& run, const Camera& camera, float time01, double exposure,
              const fs::path& png, const fs::path& exr, int png_compression, FileBatch* batch) {
  std::vector<float> ldr, hdr;
  RenderView(run.model, camera, time01, exposure, -1, &ldr, exr.empty() ? nullptr : &hdr);
  return WriteImages(ldr, hdr, camera.intrinsics.width, camera.intrinsics.height, png, exr,
                     png_compression, batch);
}

Camera AtResolution(const Camera& camera, int resolution) {
  Camera c = camera;
  c.intrinsics = method::DownscaledIntrinsics(camera.intrinsics, resolution);
  return c;
}

// --time: one view, the camera of frame options.camera_index at options.time.
int RenderAtTime(const HexPlaneRenderOptions& o, const LoadedHexPlaneRun& run,
                 const std::vector<Frame>& frames) {
  if (o.camera_index < 0 || o.camera_index >= int(frames.size()))
    Fail("render: --camera {} is not a frame of the {} split (0..{})", o.camera_index, o.split,
         frames.size() - 1);
  if (!(*o.time >= 0 && *o.time <= 1)) Fail("render: --time {} is outside [0, 1]", *o.time);
  const fs::path dir = o.out.empty() ? o.run / "renders" / "time" : o.out;
  CheckOutputFolder(dir);
  const std::string stem = fmt::format("{}_cam{:03d}_t{:.4f}", o.split, o.camera_index, *o.time);
  const Frame& f = frames[o.camera_index];
  FileBatch batch;
  const int written = WriteView(run, AtResolution(f.camera, run.resolution), *o.time,
                                o.exposure.value_or(f.exposure), dir / (stem + ".png"),
                                o.write_hdr ? dir / (stem + ".exr") : fs::path(),
                                o.png_compression, &batch);
  batch.Commit();
  fmt::print("render: {} ({} file{})\n", (dir / stem).string(), written, written == 1 ? "" : "s");
  return written;
}

// --video: the orbit of the Gaussian runs' videos (method::OrbitCameras), LDR frames only.
int RenderOrbit(const HexPlaneRenderOptions& o, const LoadedHexPlaneRun& run) {
  if (!HasLdrOutput(run.model))
    Fail("render: --video writes LDR frames, and this run ({}) has no LDR output",
         run.config.method);
  const double exposure = o.exposure.value_or(method::MedianExposure(run.dataset));
  std::vector<Camera> train_cameras;
  for (const Frame& f : run.dataset.train)
    train_cameras.push_back(AtResolution(f.camera, run.resolution));
  const std::vector<Camera> path = method::OrbitCameras(train_cameras, o.video_frames);
  const fs::path dir = o.out.empty() ? o.run / "video" : o.out;
  CheckOutputFolder(dir);
  FileBatch batch;
  Progress progress("render video", o.video_frames);
  for (int k = 0; k < o.video_frames; ++k) {
    const float time = o.video_frames > 1 ? float(k) / float(o.video_frames - 1) : 0.0f;
    WriteView(run, path[k], time, exposure, dir / fmt::format("frame_{:04d}.png", k), {},
              o.png_compression, &batch);
    progress.Advance();
  }
  progress.Finish();
  batch.Commit();
  method::FinishVideo(dir, o.video_frames, o.fps);
  return o.video_frames;
}

// Every view of the split, named like its ground truth so `hdr4d eval` pairs them (as
// method/run/render_split.cpp); with `timing`, each view's render time and the fps.
int RenderSplit(const HexPlaneRenderOptions& o, const LoadedHexPlaneRun& run,
                const std::vector<Frame>& frames) {
  const fs::path out = o.out.empty() ? o.run / "renders" / o.split : o.out;
  CheckOutputFolder(out);
  FileBatch batch;  // the renders replace an earlier run's all together (atomic_file.h)
  Progress progress("render", static_cast<std::int64_t>(frames.size()));
  std::vector<double> seconds;
  std::vector<BracketRenderer::ViewAt> at;
  for (const Frame& f : frames)
    at.push_back({AtResolution(f.camera, run.resolution), float(f.time),
                  o.exposure.value_or(f.exposure)});
  BracketRenderer renderer(run.model, at);  // a shot's brackets rendered together
  std::set<fs::path> hdr_written;           // one EXR per HDR truth, not one per bracket
  std::vector<float> ldr, hdr;
  int written = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const Frame& f = frames[i];
    fs::path name = f.image_path.filename();
    if (name.extension() != ".png") name += ".png";
    fs::path hdr_name = f.hdr_path ? f.hdr_path->filename() : f.image_path.stem();
    if (hdr_name.extension() != ".exr") hdr_name += ".exr";
    const bool with_hdr = o.write_hdr && hdr_written.insert(hdr_name).second;
    const auto start = std::chrono::steady_clock::now();
    renderer.Render(i, &ldr, with_hdr ? &hdr : nullptr);  // WriteImages skips an empty exr path
    written += WriteImages(ldr, hdr, at[i].camera.intrinsics.width, at[i].camera.intrinsics.height,
                           out / name, with_hdr ? out / hdr_name : fs::path(), o.png_compression,
                           &batch);
    seconds.push_back(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    progress.Advance();
  }
  progress.Finish();
  batch.Commit();
  if (!o.timing.empty()) {
    const std::size_t warmup = seconds.size() > 1 ? 1 : 0;
    double timed = 0;
    for (std::size_t i = warmup; i < seconds.size(); ++i) timed += seconds[i];
    const double fps = timed > 0 ? double(seconds.size() - warmup) / timed : 0.0;
    WriteJsonFile(o.timing, {{"views", seconds.size()},
                             {"warmup_views", warmup},
                             {"threads", MaxThreads()},
                             {"fps", FiniteOrNull(fps)},
                             {"view_seconds", seconds},
                             {"note",
                              "render time includes the PNG/EXR encoding; a shot's brackets are "
                              "rendered together, in its first view's time"}});
  }
  return written;
}

}  // namespace

int RenderHexPlaneRun(const HexPlaneRenderOptions& options) {
  if (options.video_frames < 0) Fail("render: video frames {} must be >= 1", options.video_frames);
  KeepFreedHeap();  // each chunk's matrices reuse the last chunk's pages (heap_policy.h)
  const LoadedHexPlaneRun run = LoadHexPlaneRun(options.run, options.resolution);
  const Split split = ParseSplit(options.split, "render");
  const std::vector<Frame>& frames = run.dataset.FramesOf(split);
  if (frames.empty())
    Fail("{}: the {} split has no frames", run.dataset.root.string(), options.split);
  if (options.time) return RenderAtTime(options, run, frames);
  if (options.video_frames > 0) return RenderOrbit(options, run);
  return RenderSplit(options, run, frames);
}

}  // namespace hdr4d::baselines::hexplane
