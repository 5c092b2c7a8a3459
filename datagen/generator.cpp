#include "datagen/generator.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <nlohmann/json.hpp>
#include <set>

#include "core/crf.h"
#include "core/dataset.h"
#include "core/error.h"
#include "core/exposure_stack.h"
#include "core/json_util.h"
#include "datagen/blender_process.h"
#include "datagen/blender_render.h"
#include "datagen/dataset_assembly.h"
#include "datagen/scene_presets.h"
#include "datagen/sha256.h"

namespace hdr4d::datagen {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kGenerator = "hdr4d datagen";
constexpr const char* kManifestFile = "manifest.json";

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

bool IsEmptyDir(const fs::path& dir) {
  std::error_code ec;
  return fs::is_directory(dir, ec) && fs::directory_iterator(dir, ec) == fs::directory_iterator();
}

// True when `dir` holds a previous datagen run (its manifest names this generator).
bool IsDatagenOutput(const fs::path& dir) {
  const fs::path manifest = dir / kManifestFile;
  std::error_code ec;
  if (!fs::is_regular_file(manifest, ec)) return false;
  try {
    const json j = ReadJsonFile(manifest);
    return j.is_object() && j.contains("generator") && j["generator"] == kGenerator;
  } catch (const Error&) {
    return false;
  }
}

// Checks that the scene may be written and returns a fresh staging folder next to it.
fs::path PrepareStaging(const fs::path& final_dir, const std::string& scene) {
  std::error_code ec;
  if (fs::exists(final_dir, ec) &&
      !(fs::is_directory(final_dir, ec) && (IsEmptyDir(final_dir) || IsDatagenOutput(final_dir)))) {
    Fail(
        "{}: exists and is not the output of a previous `hdr4d datagen` run (no manifest.json "
        "naming it); choose another --out or remove it",
        final_dir.string());
  }
  const fs::path staging = final_dir.string() + ".partial";
  if (fs::exists(staging, ec)) {
    if (!fs::is_directory(staging, ec) ||
        !(IsEmptyDir(staging) || fs::exists(staging / kPlanFile, ec))) {
      Fail("{}: exists and is not a datagen work folder; remove it to render scene '{}'",
           staging.string(), scene);
    }
    fs::remove_all(staging, ec);
    if (ec) Fail("{}: cannot remove the previous work folder: {}", staging.string(), ec.message());
  }
  fs::create_directories(staging, ec);
  if (ec || !fs::is_directory(staging)) {
    Fail("{}: cannot create the output folder: {}", staging.string(),
         ec ? ec.message() : "not a directory");
  }
  return staging;
}

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

json Checksums(const fs::path& root) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (!entry.is_regular_file()) continue;
    const fs::path relative = fs::relative(entry.path(), root);
    // The log holds timings and the manifest holds the checksums: neither is reproducible.
    if (relative == kManifestFile || relative == kLogFile) continue;
    files.push_back(relative);
  }
  std::sort(files.begin(), files.end());
  json out = json::object();
  for (const fs::path& f : files) out[f.generic_string()] = Sha256File(root / f);
  return out;
}

void MoveIntoPlace(const fs::path& staging, const fs::path& final_dir) {
  std::error_code ec;
  if (fs::exists(final_dir, ec)) {
    // Checked before rendering: empty, or a previous datagen output of this scene.
    fs::remove_all(final_dir, ec);
    if (ec) Fail("{}: cannot replace the previous output: {}", final_dir.string(), ec.message());
  }
  fs::rename(staging, final_dir, ec);
  if (ec) {
    Fail("{}: cannot move the finished scene into place from {}: {}", final_dir.string(),
         staging.string(), ec.message());
  }
}

}  // namespace

void DatagenOptions::Validate() const {
  if (scene != "all") FindScene(scene);
  if (std::find(PresetNames().begin(), PresetNames().end(), preset) == PresetNames().end())
    Fail("datagen: unknown preset '{}' (known: ci, mini, paper)", preset);
  if (out.empty()) Fail("datagen: give an output folder (--out)");
  if (threads < 0) Fail("datagen: --threads must be >= 0 (0 = every core), got {}", threads);
  if (samples < 0) Fail("datagen: --samples must be >= 0 (0 = the preset's), got {}", samples);
  if (width < 0) Fail("datagen: --width must be >= 0 (0 = the preset's), got {}", width);
  for (const std::string& name : scene == "all" ? DefaultSceneNames() : std::vector{scene})
    LdrFor(name).Validate();
}

DatasetSynthesisOptions DatagenOptions::LdrFor(const std::string& name) const {
  const SceneInfo& info = FindScene(name);
  constexpr double kFullWell = 20000, kReadSigma = 0.002;  // the eight scenes' sensor
  return {.crf = crf.value_or(info.crf),
          .noise = {.full_well = full_well.value_or(info.noise ? kFullWell : 0.0),
                    .read_sigma = read_sigma.value_or(info.noise ? kReadSigma : 0.0),
                    .seed = seed},
          .bits = 8};
}

SceneResult GenerateScene(const DatagenOptions& options, const std::string& scene) {
  options.Validate();
  const auto start = std::chrono::steady_clock::now();
  ScenePreset preset = ResolvePreset(scene, options.preset, options.width);
  if (options.samples > 0) preset.samples = options.samples;
  const std::vector<PlannedRender> renders = PlanRenders(preset);
  const fs::path final_dir = options.out / preset.scene;
  // Fail early on a missing Blender or scripts folder, before touching the output.
  FindBlender(options.blender);
  FindScriptsDir(options.scripts_dir);
  const fs::path staging = PrepareStaging(final_dir, preset.scene);
  const BlenderSettings blender{.blender = options.blender,
                                .scripts_dir = options.scripts_dir,
                                .seed = options.seed,
                                .threads = options.threads,
                                .show_progress = options.show_progress};
  const BlenderRender run = RenderWithBlender(preset, renders, blender, staging);
  const json& info = run.info;
  const LuminanceHistogram histogram = NormaliseExrs(preset, renders, staging);
  const Dataset dataset = BuildDataset(preset, renders, info, staging);
  WriteDataset(dataset, staging);
  const std::int64_t points = WritePointCloud(preset, info, staging);

  const DatasetSynthesisOptions ldr = options.LdrFor(preset.scene);
  const int ldr_images = SynthesizeDatasetLdr(staging, ldr);

  const DatasetReport report = CheckDataset(staging, {.image_check = ImageCheck::kFull});
  if (!report.ok()) {
    std::string problems;
    for (std::size_t i = 0; i < std::min<std::size_t>(5, report.problems.size()); ++i)
      problems += "\n  " + report.problems[i].ToString();
    Fail("datagen: scene '{}': the written dataset fails `hdr4d dataset check` ({} problems):{}",
         preset.scene, report.problems.size(), problems);
  }

  SceneResult result;
  result.scene = preset.scene;
  result.root = final_dir;
  result.renders = static_cast<int>(renders.size());
  result.ldr_images = ldr_images;
  result.blender_seconds = run.seconds;
  result.range = histogram.Summary();

  const std::unique_ptr<Crf> crf = ParseCrf(ldr.crf);
  const SceneInfo& scene_info = FindScene(preset.scene);
  json manifest = {
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
      {"points", {{"count", points}, {"time", 0.0}}},
  };
  result.total_seconds = SecondsSince(start);
  manifest["timing"] = {{"blender_seconds", result.blender_seconds},
                        {"seconds_per_render", result.blender_seconds / result.renders},
                        {"total_seconds", result.total_seconds}};
  manifest["files"] = Checksums(staging);
  WriteJsonFile(staging / kManifestFile, manifest);
  MoveIntoPlace(staging, final_dir);
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
