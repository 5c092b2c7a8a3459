// hdr4d datagen: render HDR-4D-Syn-style dynamic HDR scenes with Blender and write them as
// datasets (HDR ground truth, multi-exposure LDR, JSON, point3d.ply, manifest).
#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "cli/commands.h"
#include "cli/flags.h"
#include "cli/pipeline_flags.h"
#include "core/util/error.h"
#include "datagen/generator.h"
#include "datagen/scene_presets.h"

namespace hdr4d::cli {

namespace {

void PrintSceneList() {
  fmt::print("{:<9} {:<10} {:>7} {:>13} {:>13}  {}\n", "scene", "rig", "cameras", "paper t/t",
             "mini t/t", "content");
  for (const datagen::SceneInfo& s : datagen::AllScenes()) {
    fmt::print("{:<9} {:<10} {:>7} {:>13} {:>13}  {}{}\n", s.name, datagen::RigName(s.rig),
               s.cameras, fmt::format("{}/{}", s.paper_train, s.paper_test),
               fmt::format("{}/{}", s.mini_train, s.mini_test), s.in_all ? "" : "(not in all) ",
               s.description);
  }
  fmt::print(
      "presets: ci (48 px, 8 samples, 5+1 or 2+1 timestamps, <= 3 cameras), mini (200 px, 64 "
      "samples), paper (800 px, 128 samples, Table 8's counts); t/t = train/test timestamps\n");
}

// One line per scene as it is written.
void PrintSceneResult(const datagen::SceneResult& r) {
  if (r.capture) {
    fmt::print(
        "datagen: {}: capture of {} cameras x {} frames x {} brackets + {} static images{} "
        "in {} (truth in {}/truth; {} renders, Blender {:.1f} s; HDR range p99.9/p0.1 = "
        "{:.3g})\n",
        r.scene, r.cameras, r.frames, r.brackets, r.cameras,
        r.extra_views > 0 ? fmt::format(" + {} hand-held views", r.extra_views) : "",
        r.root.string(), r.root.string(), r.renders, r.blender_seconds, r.range.ratio);
  } else if (!r.renders_reused_from.empty()) {
    fmt::print(
        "datagen: {}: {} renders reused from {}, {} LDR images in {} ({:.1f} s; HDR range "
        "p99.9/p0.1 = {:.3g})\n",
        r.scene, r.renders, r.renders_reused_from.string(), r.ldr_images, r.root.string(),
        r.total_seconds, r.range.ratio);
  } else {
    fmt::print(
        "datagen: {}: {} renders, {} LDR images in {} (Blender {:.1f} s, {:.2f} s per render; "
        "HDR range p99.9/p0.1 = {:.3g})\n",
        r.scene, r.renders, r.ldr_images, r.root.string(), r.blender_seconds,
        r.blender_seconds / r.renders, r.range.ratio);
  }
  if (!r.val_split.empty())
    fmt::print("datagen: {}: val split: {} (--val-every 0 keeps the paper's splits)\n", r.scene,
               r.val_split);
  std::fflush(stdout);
}

// "WxH" or "B[:SIGMA]": a number, then optionally the separator and a second number. False for
// anything else.
bool ParsePair(const std::string& text, char separator, double* first, double* second) {
  const std::size_t at = text.find(separator);
  try {
    std::size_t used = 0;
    *first = std::stod(text.substr(0, at), &used);
    if (used != text.substr(0, at).size()) return false;
    if (at == std::string::npos) return true;  // the second keeps its default
    *second = std::stod(text.substr(at + 1), &used);
    return used == text.size() - at - 1;
  } catch (const std::exception&) {
    return false;
  }
}

// The capture variants issue 54 tests calibrate on: size, dense brackets, pedestal, lenses.
void AddCaptureVariantFlags(CLI::App* cmd, datagen::DatagenOptions* options) {
  cmd->add_option_function<std::string>(
         "--size",
         [options](const std::string& text) {
           double w = 0, h = 0;
           if (text.find('x') == std::string::npos || !ParsePair(text, 'x', &w, &h) ||
               w != std::floor(w) || h != std::floor(h) || w < 1 || h < 1 || w > 1e5 || h > 1e5)
             throw CLI::ValidationError("--size", "'" + text + "': give WIDTHxHEIGHT, e.g. 320x240");
           options->width = static_cast<int>(w);
           options->height = static_cast<int>(h);
         },
         "With --capture: image size WIDTHxHEIGHT in pixels (64x48 to 8192x8192; the field of view "
         "stays horizontal), instead of --width (not with it) and the scene's aspect")
      ->type_name("WxH")
      ->check(Text("WIDTHxHEIGHT"));  // parsed and range-checked by the function above
  cmd->add_option("--dense-brackets", options->dense_brackets,
                  "With --capture: N brackets one stop apart centred on 2 s (3 to 20), instead of "
                  "--brackets; with --black-level, a dense stack whose shadows test the fusion")
      ->check(Integer(0, 20));
  cmd->add_option_function<std::string>(
         "--black-level",
         [options](const std::string& text) {
           double black = 0, noise = 0;
           if (!ParsePair(text, ':', &black, &noise))
             throw CLI::ValidationError("--black-level", "'" + text + "': give CODES or CODES:SIGMA, e.g. 16:1.5");
           options->black_level = black;
           options->black_noise = noise;
         },
         "With --capture: a sensor pedestal of B 8-bit codes (0 to 64) and Gaussian dark noise of "
         "SIGMA codes around it (0 to 16), as B or B:SIGMA; recorded in truth/cameras.json")
      ->type_name("B[:SIGMA]")
      ->check(Text("B[:SIGMA]"));  // parsed by the function above; ranges in Validate()
  cmd->add_option("--lenses", options->lenses,
                  "With --capture: none, distortion (each camera its own radial k1 in 0.03-0.10, k2 "
                  "in 0-0.03, pincushion), vignetting (its own fall-off 1 - a r^2 to the corner, a "
                  "in 0.05-0.25) or both; truth/cameras.json records them, truth/ keeps the "
                  "pinhole renders")
      ->check(OneOf(datagen::CaptureLensModes()))
      ->capture_default_str();
}

// --capture and the flags that shape a capture.
void AddCaptureFlags(CLI::App* cmd, datagen::DatagenOptions* options) {
  cmd->add_flag("--capture", options->capture,
                "Write the capture layout `hdr4d calibrate` reads instead of a dataset: "
                "static/<camera>/static.png (the empty scene), sequence/<camera>/<frame>_<k>.png "
                "brackets, exposures.json, timestamps.json, and truth/ (the original dataset, "
                "the true cameras and response); one --scene, room is made for it");
  cmd->add_option("--cameras", options->cameras,
                  "With --capture: rig cameras, 30 degrees apart, the last one held out (0 = 6)")
      ->check(Integer(0, 1000))
      ->capture_default_str();
  cmd->add_option("--frames", options->frames,
                  "With --capture: timestamps of the sequence (0 = the preset's)")
      ->check(Integer(0, 100000))
      ->capture_default_str();
  cmd->add_option("--extra-views", options->extra_views,
                  "With --capture: hand-held views of the empty scene in static/extra/ (they help "
                  "COLMAP, calibrate drops them)")
      ->check(Integer(0, 100000))
      ->capture_default_str();
  cmd->add_option("--brackets", options->brackets,
                  "With --capture: bracket exposure times in seconds, increasing, comma-separated "
                  "(default: the scene's 0.125,2,32)")
      ->delimiter(',')
      ->check(PositiveReal(1e6));
  cmd->add_option("--unlike-cameras", options->unlike_cameras,
                  "With --capture: none, gains (a gain per camera and channel), responses (each "
                  "camera's response bent to crf(x^e), e in [0.9, 1.1]) or both; camera 0 is "
                  "the reference")
      ->check(OneOf(datagen::UnlikeCamerasModes()))
      ->capture_default_str();
  AddCaptureVariantFlags(cmd, options);
}

// The LDR images' camera response and sensor noise (the scene's own where not given).
void AddLdrSynthesisFlags(CLI::App* cmd, datagen::DatagenOptions* options) {
  cmd->add_option("--crf", options->crf,
                  "Camera response of the LDR images: linear, gamma:G, srgb, filmic[:k,mid], "
                  "naka-rushton:k,gamma, table:F.csv (default: the scene's, filmic for the eight)")
      ->check(Text("a camera response"));
  cmd->add_option("--full-well", options->full_well,
                  "Shot noise: photo-electrons at saturation, 0 = none (default: the scene's, "
                  "20000 for the eight, none for studio)")
      ->check(Real(0, 1e12));
  cmd->add_option("--read-noise", options->read_sigma,
                  "Read noise std in units of full scale (default: the scene's, 0.002 for the "
                  "eight, none for studio)")
      ->check(Real(0, 1));
}

// What is rendered and how: Cycles threads and samples, the point cloud, reused renders, the
// val split, the width.
void AddRenderFlags(CLI::App* cmd, datagen::DatagenOptions* options) {
  cmd->add_option("--threads", options->threads, "Cycles threads (0 = every core)")
      ->check(Integer(0, 4096))
      ->capture_default_str();
  cmd->add_option("--samples", options->samples, "Cycles samples per pixel (0 = the preset's)")
      ->check(Integer(0, 1'000'000))
      ->capture_default_str();
  cmd->add_option("--points", options->points,
                  "Surface points in point3d.ply, sampled over the scene's time (0 = the "
                  "preset's: 2000 ci, 20000 mini, 100000 paper)")
      ->check(Integer(0, 10'000'000))
      ->capture_default_str();
  cmd->add_option("--reuse-renders", options->reuse_renders,
                  "Take each scene's renders from DIR/<scene> (an earlier datagen --out DIR) "
                  "when it was rendered from the same plan (scene, preset, seed, width, samples, "
                  "points): only the LDR synthesis runs, e.g. for another --pipeline; otherwise "
                  "render, saying why")
      ->check(Text("a folder"));
  cmd->add_option_function<int>(
         "--val-every", [options](int k) { options->val_every = k; },
         "Move every frame of one training time in K to transforms_val.json, so that `hdr4d "
         "train` stops once those views stop improving (0: the paper's train and test splits "
         "only). Default: 8 for a scene of one moving camera with 16 or more training times "
         "(the mini and paper presets of airplane, deer, lego, tank), else 0")
      ->check(Integer(0, 1'000'000));
  cmd->add_option("--width", options->width,
                  "Image width in pixels (0 = the preset's; the height follows the scene): at "
                  "most 8192, and a scene's renders at most 16 GiB of float RGB (12 bytes a "
                  "pixel, e.g. 350 renders of 4096x4096 are 65.6 GiB); with --capture at "
                  "least 64x48, as --size")
      ->check(Integer(0, datagen::kMaxImageSide))
      ->capture_default_str();
}

}  // namespace

void AddDatagenCommand(CLI::App& app) {
  auto options = std::make_shared<datagen::DatagenOptions>();
  auto out = std::make_shared<std::string>();
  auto list = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "datagen",
      "Render HDR-4D-Syn-style dynamic HDR scenes with Blender (Cycles on the CPU, linear float "
      "EXR) and write each as a dataset: LDR at 0.125/2/32 s through a camera response with "
      "noise, transforms_{train,test}.json (and _val for one moving camera), point3d.ply "
      "sampled over the scene's time, manifest.json with checksums.\n"
      "  hdr4d datagen --scene all --preset mini --out DATA     (DATA/<scene>/ per scene)\n"
      "  hdr4d datagen --capture --scene room --width 240 --out CAP   (a rig capture for "
      "hdr4d calibrate)\n"
      "  hdr4d datagen --list");
  cmd->add_option("--scene", options->scene, "A scene name (see --list) or all")
      ->check(Text("a scene name or all"))
      ->capture_default_str();
  cmd->add_option("--preset", options->preset, "ci, mini or paper")
      ->check(OneOf(datagen::PresetNames()))
      ->capture_default_str();
  cmd->add_option("--out,-o", *out,
                  "Output folder: one sub-folder per scene. A rerun replaces a scene folder "
                  "datagen wrote, deleting only the files its manifest.json lists; one that "
                  "holds anything else is refused, naming it")
      ->check(Text("an output folder"));
  cmd->add_option("--seed", options->seed,
                  "Seed of the render, camera wobble, point sampling and LDR noise (same seed, "
                  "same bytes)")
      ->check(Seed())
      ->capture_default_str();
  cmd->add_option("--blender", options->blender,
                  "Blender executable (default: $HDR4D_BLENDER, then blender on PATH)")
      ->check(Text("a Blender executable"));
  cmd->add_option("--scripts-dir", options->scripts_dir,
                  "Folder of the bpy scripts (default: $HDR4D_DATAGEN_DIR, then datagen/blender "
                  "in the source tree)")
      ->check(Text("a folder"));
  AddRenderFlags(cmd, options.get());
  AddLdrSynthesisFlags(cmd, options.get());
  AddCaptureFlags(cmd, options.get());
  cmd->add_flag("--list", *list, "List the scenes and presets, render nothing");
  auto pipeline = std::make_shared<PipelineFlags>(cmd, options->pipeline);
  cmd->callback([cmd, options, out, list, pipeline] {
    pipeline->Check();
    // Both set the width; neither silently wins.
    if (cmd->count("--size") > 0 && cmd->count("--width") > 0)
      Fail("datagen: --size and --width both set the image width; give one (--size WxH for a "
           "capture's exact size, --width for the scene's aspect)");
    if (*list) {
      PrintSceneList();
      return;
    }
    options->out = *out;
    datagen::Generate(*options, PrintSceneResult);
  });
}

}  // namespace hdr4d::cli
