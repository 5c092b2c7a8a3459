#include "datagen/generator.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>

#include "core/radiometry/crf.h"
#include "core/dataset/dataset.h"
#include "core/dataset/val_split.h"
#include "core/util/error.h"
#include "core/radiometry/exposure_stack.h"
#include "core/files/json_util.h"
#include "core/geometry/ply.h"
#include "datagen/blender_process.h"
#include "datagen/blender_render.h"
#include "datagen/capture_generator.h"
#include "datagen/dataset_assembly.h"
#include "datagen/output_folder.h"
#include "datagen/scene_presets.h"

namespace hdr4d::datagen {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

json SplitCounts(const std::vector<PlannedRender>& renders, Split split) {
  std::set<int> times;
  int hdr = 0, ldr = 0;
  for (const PlannedRender& r : renders) {
    if (r.split != split) continue;
    times.insert(r.time_index);
    ++hdr;
    ldr += static_cast<int>(r.exposure_indices.size());
  }
  return {{"frames", times.size()}, {"hdr", hdr}, {"ldr", ldr}};
}

}  // namespace

int DatagenOptions::ValEveryFor(const ScenePreset& preset) const {
  if (val_every) return *val_every;
  return preset.rig == Rig::kMonocular && preset.train_timestamps >= kMinTimesForMonocularVal
             ? kMonocularValEvery
             : 0;
}

void DatagenOptions::Validate() const {
  if (scene != "all") FindScene(scene);
  if (std::find(PresetNames().begin(), PresetNames().end(), preset) == PresetNames().end())
    Fail("datagen: unknown preset '{}' (known: ci, mini, paper)", preset);
  if (out.empty()) Fail("datagen: give an output folder (--out)");
  if (threads < 0) Fail("datagen: --threads must be >= 0 (0 = every core), got {}", threads);
  if (samples < 0) Fail("datagen: --samples must be >= 0 (0 = the preset's), got {}", samples);
  if (width < 0) Fail("datagen: --width must be >= 0 (0 = the preset's), got {}", width);
  if (!capture && height == 0 && width > kMaxImageSide)  // a capture says it as --size does
    Fail("datagen: --width {}: at most {} pixels (a float RGB frame of {}x{} is 0.8 GB, held a "
         "few times over by Cycles and datagen)", width, kMaxImageSide, kMaxImageSide,
         kMaxImageSide);
  if (points < 0 || points > 10'000'000)
    Fail("datagen: --points must be in [0, 10^7] (0 = the preset's), got {}", points);
  if (points != 0 && capture)
    Fail("datagen: --points sets a dataset's point3d.ply; a capture keeps the preset's");
  if (val_every && (*val_every < 0 || *val_every == 1))
    Fail("datagen: --val-every {}: give K >= 2 (one training time in K to val) or 0 (none)",
         *val_every);
  if (val_every.value_or(0) != 0 && capture)
    Fail("datagen: --val-every splits a dataset's training frames; a capture has none (split the "
         "calibrated dataset with `hdr4d dataset split-val`)");
  if (std::find(UnlikeCamerasModes().begin(), UnlikeCamerasModes().end(), unlike_cameras) ==
      UnlikeCamerasModes().end())
    Fail("datagen: --unlike-cameras {}: use none, gains, responses or both", unlike_cameras);
  if (!capture) {
    const char* flag = cameras != 0              ? "--cameras"
                       : frames != 0             ? "--frames"
                       : extra_views != 0        ? "--extra-views"
                       : !brackets.empty()       ? "--brackets"
                       : unlike_cameras != "none" ? "--unlike-cameras"
                                                 : CaptureVariantFlag(*this);
    if (flag != nullptr)
      Fail("datagen: {} describes a capture rig and needs --capture (a dataset keeps its scene's "
           "own cameras and timestamps)", flag);
  } else {
    if (scene == "all")
      Fail("datagen: --capture renders one scene; give --scene (room is made for it: textured "
           "floor and walls that COLMAP can match)");
    if (cameras != 0 && (cameras < 2 || cameras > kCaptureMaxCameras))
      Fail("datagen: --cameras {}: a capture rig has 2 to {} cameras (30 degrees apart, the last "
           "one held out), or 0 for {}", cameras, kCaptureMaxCameras, kCaptureCameras);
    if (frames != 0 && frames < 2)
      Fail("datagen: --frames {}: a capture needs at least 2 frames (0 = the preset's)", frames);
    if (extra_views < 0 || extra_views > 100)
      Fail("datagen: --extra-views {}: use 0 to 100 hand-held views", extra_views);
    if (!brackets.empty()) {
      if (brackets.size() < 2)
        Fail("datagen: --brackets: {} exposure time; a capture needs at least two",
             brackets.size());
      for (std::size_t k = 0; k < brackets.size(); ++k) {
        if (!(brackets[k] > 0) || !std::isfinite(brackets[k]))
          Fail("datagen: --brackets: {} is not a positive exposure time in seconds", brackets[k]);
        if (k > 0 && !(brackets[k] > brackets[k - 1]))
          Fail("datagen: --brackets: {} after {}: give the times in increasing order, each once",
               brackets[k], brackets[k - 1]);
      }
    }
  }
  if (capture) ValidateCaptureVariant(*this);
  if (capture && !reuse_renders.empty())
    Fail("datagen: --reuse-renders takes the renders of a dataset; a capture renders its own");
  if (capture && !pipeline.IsIdentity())
    Fail("datagen: --pipeline and --vignetting make datasets, not captures: a capture's cameras "
         "differ through --unlike-cameras");
  for (const std::string& name : scene == "all" ? DefaultSceneNames() : std::vector{scene}) {
    LdrFor(name).Validate();
    if (capture) {
      const ScenePreset p = CapturePreset(*this, name);
      CheckRenderBudget(p, CaptureRenders(p).size());
    } else {
      const ScenePreset p = ResolvePreset(name, preset, width);
      CheckRenderBudget(p, PlanRenders(p).size());
    }
  }
}

void CheckRenderBudget(const ScenePreset& preset, std::size_t renders) {
  const double gib = static_cast<double>(renders) * preset.width * preset.height * 12 /
                     (1024.0 * 1024.0 * 1024.0);
  if (gib <= kMaxRenderGiB) return;
  Fail("datagen: scene '{}': {} renders of {}x{} are {:.1f} GiB of float RGB (12 bytes a pixel "
       "before compression); a scene may have at most {:.0f} GiB: lower --width{}, or use a "
       "smaller --preset", preset.scene, renders, preset.width, preset.height, gib,
       kMaxRenderGiB, preset.layout == "capture" ? " or --size, --frames, --cameras" : "");
}

BlenderSettings DatagenOptions::FoundBlender() const {
  FindBlender(blender);
  FindScriptsDir(scripts_dir);
  return {.blender = blender,
          .scripts_dir = scripts_dir,
          .seed = seed,
          .threads = threads,
          .show_progress = show_progress};
}

DatasetSynthesisOptions DatagenOptions::LdrFor(const std::string& name) const {
  const SceneInfo& info = FindScene(name);
  constexpr double kFullWell = 20000, kReadSigma = 0.002;  // the eight scenes' sensor
  CameraPipelineOptions scene_pipeline = pipeline;
  scene_pipeline.seed = seed;
  return {.crf = crf.value_or(info.crf),
          .noise = {.full_well = full_well.value_or(info.noise ? kFullWell : 0.0),
                    .read_sigma = read_sigma.value_or(info.noise ? kReadSigma : 0.0),
                    .seed = seed},
          .bits = 8,
          .pipeline = scene_pipeline};
}

const std::vector<std::string>& UnlikeCamerasModes() {
  static const std::vector<std::string> modes = {"none", "gains", "responses", "both"};
  return modes;
}

namespace {

// The written dataset must pass `hdr4d dataset check` with every image read; the first five
// problems are named.
void CheckWrittenDataset(const fs::path& staging, const std::string& scene) {
  const DatasetReport report = CheckDataset(staging, {.image_check = ImageCheck::kFull});
  if (!report.ok()) {
    std::string problems;
    for (std::size_t i = 0; i < std::min<std::size_t>(5, report.problems.size()); ++i)
      problems += "\n  " + report.problems[i].ToString();
    Fail("datagen: scene '{}': the written dataset fails `hdr4d dataset check` ({} problems):{}",
         scene, report.problems.size(), problems);
  }
}

// What made the scene and what it holds: generator, Blender and render settings, rig, counts,
// LDR synthesis, dynamic range, points (manifest.json, datagen/output_folder.h).
json SceneManifest(const DatagenOptions& options,
                   const ScenePreset& preset,
                   const std::vector<PlannedRender>& renders,
                   const json& info,
                   const Dataset& dataset,
                   const DatasetSynthesisOptions& ldr,
                   const SceneResult& result,
                   std::int64_t points) {
  const std::unique_ptr<Crf> crf = ParseCrf(ldr.crf);
  const SceneInfo& scene_info = FindScene(preset.scene);
  return {
      {"generator", kGenerator},
      {"generator_version",
       fmt::format("hdr4d {}, datagen format {}, scripts {}", HDR4D_DATAGEN_VERSION,
                   kPlanFormatVersion, info.value("script_version", 0))},
      {"scene", preset.scene},
      {"description", scene_info.description},
      {"preset", preset.preset},
      {"seed", options.seed},
      {"blender_version", info["blender_version"]},
      {"render",
       {{"engine", "CYCLES"},
        {"device", "CPU"},
        {"samples", preset.samples},
        {"adaptive_sampling", false},
        {"denoising", false},
        {"width", preset.width},
        {"height", preset.height},
        {"threads", options.threads},
        {"view_transform", "Standard"},
        {"hdr_format",
         "OpenEXR, float32 RGB, ZIP; linear scene radiance (rewritten losslessly without "
         "Cycles' timing metadata)"}}},
      {"rig", RigName(preset.rig)},
      {"cameras", preset.cameras},
      {"held_out_cameras", preset.held_out_cameras},
      {"camera_angle_x", dataset.camera_angle_x},
      {"exposures", preset.exposures},
      {"exposure_pattern", ExposurePatternName(preset.exposure_pattern)},
      {"counts",
       {{"train", SplitCounts(renders, Split::kTrain)},
        {"test", SplitCounts(renders, Split::kTest)}}},
      {"ldr_synthesis",
       {{"crf", crf->ToJson()},
        {"crf_spec", crf->Spec()},
        {"full_well", ldr.noise.full_well},
        {"read_sigma", ldr.noise.read_sigma},
        {"noise_seed", options.seed},
        {"bits", 8}}},
      {"dynamic_range",
       {{"p0.1", result.range.p001},
        {"p99.9", result.range.p999},
        {"ratio_p99.9_p0.1", result.range.ratio},
        {"min_positive", result.range.min_positive},
        {"max", result.range.max},
        {"zero_fraction", result.range.zero_fraction}}},
      {"points",
       {{"count", points},
        {"times", info.contains("points") && info["points"].contains("times")
                      ? info["points"]["times"]
                      : json::array({0.0})}}},
  };
}

// The scene's renders: Blender's, or with --reuse-renders an earlier dataset's of the same plan.
BlenderRender Renders(const DatagenOptions& options,
                      const ScenePreset& preset,
                      const std::vector<PlannedRender>& renders,
                      const fs::path& staging,
                      SceneResult* result) {
  if (!options.reuse_renders.empty()) {
    const fs::path source = options.reuse_renders / preset.scene;
    std::string why;
    const BlenderSettings settings{.seed = options.seed, .threads = options.threads};
    if (auto reused = ReuseRenders(preset, renders, settings, source, staging, &why)) {
      result->renders_reused_from = source;
      return *reused;
    }
    fmt::print(stderr, "datagen: {}: not reusing renders: {}; rendering with Blender\n",
               preset.scene, why);
  }
  return RenderWithBlender(preset, renders, options.FoundBlender(), staging);
}

// point3d.ply: from Blender's surface points, or the reused dataset's own file.
std::int64_t PointCloudFile(const ScenePreset& preset, const json& info,
                            const SceneResult& result, const fs::path& staging) {
  if (result.renders_reused_from.empty()) return WritePointCloud(preset, info, staging);
  const fs::path ply = staging / "point3d.ply";
  fs::copy_file(result.renders_reused_from / "point3d.ply", ply,
                fs::copy_options::overwrite_existing);
  const std::int64_t count = static_cast<std::int64_t>(ReadPly(ply).size());
  const std::int64_t expected = info.contains("points") ? info["points"].value("count", -1) : -1;
  if (count != expected)
    Fail("datagen: scene '{}': {} holds {} points, its render_info.json says {}", preset.scene,
         (result.renders_reused_from / "point3d.ply").string(), count, expected);
  return count;
}

}  // namespace

SceneResult GenerateScene(const DatagenOptions& options, const std::string& scene) {
  options.Validate();
  if (options.capture) return GenerateCapture(options, scene);
  const auto start = std::chrono::steady_clock::now();
  ScenePreset preset = ResolvePreset(scene, options.preset, options.width);
  if (options.samples > 0) preset.samples = options.samples;
  if (options.points > 0) preset.points = options.points;
  const std::vector<PlannedRender> renders = PlanRenders(preset);
  const fs::path final_dir = options.out / preset.scene;
  if (options.reuse_renders.empty()) options.FoundBlender();  // a missing Blender, before anything
  const fs::path staging = PrepareStaging(final_dir, preset.scene);
  SceneResult result;
  const BlenderRender run = Renders(options, preset, renders, staging, &result);
  const json& info = run.info;
  const LuminanceHistogram histogram = NormaliseExrs(preset, renders, staging);
  const Dataset dataset = BuildDataset(preset, renders, info, staging);
  WriteDataset(dataset, staging);
  const std::int64_t points = PointCloudFile(preset, info, result, staging);

  const DatasetSynthesisOptions ldr = options.LdrFor(preset.scene);
  const int ldr_images = SynthesizeDatasetLdr(staging, ldr);
  if (const int k = options.ValEveryFor(preset); k > 0) {
    ValSplitOptions val{.every_time = k, .every_time_flag = "--val-every"};
    const ValSplitSummary moved = SplitValInPlace(staging, val, "datagen");
    result.val_frames = static_cast<int>(moved.moved);
    result.val_split = fmt::format("{} of {} training frames to val ({})", moved.moved,
                                   moved.moved + moved.kept, moved.what);
  }
  CheckWrittenDataset(staging, preset.scene);

  result.scene = preset.scene;
  result.root = final_dir;
  result.renders = static_cast<int>(renders.size());
  result.ldr_images = ldr_images;
  result.blender_seconds = run.seconds;
  result.range = histogram.Summary();
  json manifest = SceneManifest(options, preset, renders, info, dataset, ldr, result, points);
  if (!result.renders_reused_from.empty())
    manifest["renders_reused_from"] = result.renders_reused_from.string();
  if (result.val_frames > 0) {
    manifest["val_split"] = {{"val_every", options.ValEveryFor(preset)},
                             {"frames", result.val_frames},
                             {"what", result.val_split}};
  }
  result.total_seconds = FinishOutput(std::move(manifest), result.blender_seconds, result.renders,
                                      start, staging, final_dir);
  return result;
}

std::vector<SceneResult> Generate(const DatagenOptions& options,
                                  const std::function<void(const SceneResult&)>& on_done) {
  options.Validate();
  const std::vector<std::string> names =
      options.scene == "all" ? DefaultSceneNames() : std::vector<std::string>{options.scene};
  std::vector<SceneResult> results;
  for (const std::string& name : names) {
    results.push_back(GenerateScene(options, name));
    if (on_done) on_done(results.back());
  }
  return results;
}

}  // namespace hdr4d::datagen
