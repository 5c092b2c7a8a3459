// Running the bpy script (datagen/blender/render_scene.py) on a render plan: the plan is written
// as render_plan.json in the scene's work folder, Blender runs headless with its output kept in
// blender.log and each "HDR4D_RENDERED i n" line advancing a progress bar, and what the script
// reports (render_info.json: Blender's version, every camera-to-world matrix, marker positions)
// is read back and checked against the plan.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "datagen/scene_presets.h"

namespace hdr4d::datagen {

// File names inside a scene's folder.
inline constexpr const char* kPlanFile = "render_plan.json";
inline constexpr const char* kInfoFile = "render_info.json";
// float32 x y z r g b t per point (x y z r g b at t = 0 before script version 2); the name is
// kept from then.
inline constexpr const char* kPointsFile = "points_t0.bin";
inline constexpr const char* kLogFile = "blender.log";
// Bumped when the plan, the scripts' output or the dataset they make changes meaning.
inline constexpr int kPlanFormatVersion = 2;  // 2: point_times (issue 56)

struct BlenderSettings {
  std::string blender;      // see FindBlender
  std::string scripts_dir;  // see FindScriptsDir
  std::uint64_t seed = 0;
  int threads = 0;  // Cycles threads, 0 = every core
  bool show_progress = true;
};

struct BlenderRender {
  double seconds = 0;   // Blender's wall time
  nlohmann::json info;  // render_info.json, one "renders" entry per planned render, in order
};

// What render_scene.py reads.
nlohmann::json RenderPlanJson(const ScenePreset& preset,
                              const std::vector<PlannedRender>& renders,
                              const BlenderSettings& settings);

// Writes the plan into `staging`, renders it and reads render_info.json. Throws hdr4d::Error
// naming the scene, the frame being rendered, Python's last exception and the log for a
// non-zero exit, and naming the file for a missing or malformed render_info.json.
BlenderRender RenderWithBlender(const ScenePreset& preset,
                                const std::vector<PlannedRender>& renders,
                                const BlenderSettings& settings,
                                const std::filesystem::path& staging);

// --reuse-renders: the renders of `source`, a scene folder datagen wrote from the same render
// plan (scene, preset, seed, size, samples, points; Cycles' thread count aside), copied into
// `staging` as Blender leaves them: each planned EXR, render_info.json (checked against the plan
// as after a render) and blender.log; this call's plan is written as render_plan.json. The LDR
// synthesis (the camera pipeline) is not part of the plan, so one render serves every pipeline
// of a scene. Returns nullopt with the reason in *why when `source` holds no dataset of this
// plan (none there, another plan, a planned file missing); nothing is then left in `staging`
// that a render would not replace.
std::optional<BlenderRender> ReuseRenders(const ScenePreset& preset,
                                          const std::vector<PlannedRender>& renders,
                                          const BlenderSettings& settings,
                                          const std::filesystem::path& source,
                                          const std::filesystem::path& staging,
                                          std::string* why);

}  // namespace hdr4d::datagen
