// Turning Blender's output into a dataset (ARCHITECTURE §3): the EXRs checked and rewritten without
// Cycles' timing metadata, one Frame per render and exposure, point3d.ply from the surface
// samples over the scene's time.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/dataset/dataset.h"
#include "core/image/image.h"
#include "datagen/dynamic_range.h"
#include "datagen/scene_presets.h"

namespace hdr4d::datagen {

// Reads every planned EXR in `staging` (a missing or corrupt one, or a wrong size, is an error
// naming the scene, the frame and the file) and rewrites it as float EXR with core's WriteImage
// (no render times or dates in the header, so equal renders give equal bytes). Returns
// the luminance histogram of all frames.
LuminanceHistogram NormaliseExrs(const ScenePreset& preset,
                                 const std::vector<PlannedRender>& renders,
                                 const std::filesystem::path& staging);

// The dataset of the renders: per render and exposure a frame with its LDR file_path (images/,
// written later by the LDR synthesis), exr_file_path, time, exposure, camera_id,
// exposure_index, and the camera Blender reported in `info` (render_info.json).
Dataset BuildDataset(const ScenePreset& preset,
                     const std::vector<PlannedRender>& renders,
                     const nlohmann::json& info,
                     const std::filesystem::path& staging);

// point3d.ply (x y z, uchar colour, float time) from the script's surface samples, which are
// then removed: each point carries the time it was sampled at, inside (0, 1) (render_info.json's
// points.times; t = 0 for a script before version 2, which reported none). Returns the number
// of points. Throws hdr4d::Error naming the file for a wrong size or a time outside (0, 1).
std::int64_t WritePointCloud(const ScenePreset& preset,
                             const nlohmann::json& info,
                             const std::filesystem::path& staging);

}  // namespace hdr4d::datagen
