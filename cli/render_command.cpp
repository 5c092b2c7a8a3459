// hdr4d render: images of a trained run.
#include <fmt/format.h>

#include "baselines/hexplane/hexplane_render.h"
#include "cli/commands.h"
#include "cli/flags.h"
#include "core/util/error.h"
#include "core/util/parallel.h"
#include "method/run/render_split.h"

namespace hdr4d::cli {

namespace {

// A run of the grid family (HexPlane) renders through its own engine, with the same options;
// true when `options.run` is one.
bool RenderGridRunIfAsked(const method::RenderRunOptions& options) {
  if (!baselines::hexplane::IsHexPlaneRun(options.run)) return false;
  const ThreadLimit limit(options.threads);
  const int n = baselines::hexplane::RenderHexPlaneRun(
      {.run = options.run, .out = options.out, .split = options.split,
       .resolution = options.resolution, .exposure = options.exposure,
       .write_hdr = options.write_hdr, .png_compression = options.png_compression,
       .time = options.time, .camera_index = options.camera_index,
       .video_frames = options.video_frames, .fps = options.fps, .timing = options.timing});
  if (!options.time && options.video_frames == 0) fmt::print("render: wrote {} images\n", n);
  return true;
}

// How the images are written: resolution, PNG compression, the per-view timing file.
void AddOutputFlags(CLI::App* cmd, method::RenderRunOptions* options, std::string* timing) {
  cmd->add_option("--timing", *timing,
                  "Write each view's render time and the fps after a one-view warm-up to this "
                  "JSON file (split renders)")
      ->check(Text("a timing file"));
  cmd->add_option("--resolution", options->resolution,
                  "Render at the scene's images reduced R times (1: full size) instead of the "
                  "run's own training resolution (0); scores against the truth with `hdr4d eval "
                  "--resolution R`")
      ->check(Integer(0, 65536))
      ->capture_default_str();
  cmd->add_option("--png-compression", options->png_compression,
                  "zlib level of the LDR PNGs, 0 (none) to 9 (smallest): 1, the default, writes "
                  "an 800x800 render about 3x faster than PNG's usual 6 for files 30-45% larger")
      ->check(Integer(0, 9))
      ->capture_default_str();
}

}  // namespace

void AddRenderCommand(CLI::App& app) {
  auto options = std::make_shared<method::RenderRunOptions>();
  auto run = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "render",
      "Render a trained run's views of a split: the LDR image (PNG, at each view's exposure or "
      "--exposure) and, for HDR models, the linear HDR image (EXR). Each is named like its ground "
      "truth (file_path, exr_file_path), so `hdr4d eval OUT <scene image folder>` scores them.");
  cmd->add_option("--run", *run, "Run folder (from hdr4d train)")
      ->required()
      ->check(Text("a run folder"));
  cmd->add_option("--out", *out, "Output folder (default RUN/renders/<split>)")
      ->check(Text("an output folder"));
  cmd->add_option("--split", options->split, "train, test or val")
      ->check(OneOf({"train", "test", "val"}))
      ->capture_default_str();
  cmd->add_option("--threads", options->threads, "Threads (0 = all cores)")
      ->check(Integer(0, 4096))
      ->capture_default_str();
  auto time = std::make_shared<float>(0.0f);
  CLI::Option* time_option =
      cmd->add_option("--time", *time,
                      "Render one view at this normalised time in [0,1] (with --camera)")
          ->check(Real(0, 1));
  cmd->add_option("--camera", options->camera_index,
                  "With --time: the camera of this frame of the split")
      ->check(Integer(0))
      ->needs(time_option)
      ->capture_default_str();
  CLI::Option* video_option =
      cmd->add_option("--video", options->video_frames,
                      "Render N frames orbiting the scene while time runs 0..1 (PNG sequence; MP4 "
                      "with ffmpeg)")
          ->check(Integer(1, 1'000'000))
          ->excludes(time_option);
  cmd->add_option("--fps", options->fps, "Video frame rate")
      ->check(Integer(1, 1000))
      ->needs(video_option)
      ->capture_default_str();
  auto exposure = std::make_shared<double>(1.0);
  CLI::Option* exposure_option =
      cmd->add_option("--exposure", *exposure,
                      "LDR renders at this exposure in seconds (default: each view's own; the "
                      "median training exposure for --video)")
          ->check(PositiveReal());
  auto timing = std::make_shared<std::string>();
  AddOutputFlags(cmd, options.get(), timing.get());
  auto no_hdr = std::make_shared<bool>(false);
  cmd->add_flag("--no-hdr", *no_hdr,
                "Do not write the HDR (EXR) renders (nor blend the HDR channels: about 10% faster "
                "for HDR-4DGS, the same LDR images)");
  cmd->callback([options, run, out, time, time_option, exposure, exposure_option, no_hdr, timing] {
    options->timing = *timing;
    if (time_option->count() > 0) options->time = *time;
    if (exposure_option->count() > 0) options->exposure = *exposure;
    options->write_hdr = !*no_hdr;
    options->run = *run;
    options->out = *out;
    method::ProtectRunInputs(*run, method::RenderOutputFolder(*options));
    if (RenderGridRunIfAsked(*options)) return;
    const int n = method::RenderRun(*options);
    fmt::print("render: wrote {} images\n", n);
  });
}

}  // namespace hdr4d::cli
