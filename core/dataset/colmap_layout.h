// HDR-GS's COLMAP scene layout (its synthetic release), read into a Dataset:
//   images/<view>_<k>.png   k = 0..4, exposures 0.125, 0.5, 2, 8, 32 s (hard-coded by HDR-GS)
//   exr/<view>.exr          HDR ground truth per view (optional)
//   sparse/0/               COLMAP model with one image per view (its name's _k suffix, if
//                           any, is ignored: every exposure shares the view's pose)
// Static scene: every frame has time 0. Split as HDR-GS: views sorted by name in pairs; the
// first of each pair trains at exposures k = 0, 2, 4, the second is the test view at all five.
#pragma once

#include <filesystem>

#include "core/dataset/dataset.h"

namespace hdr4d {

// True when `root` has sparse/ and images/ but no transforms JSON.
bool IsHdrGsColmapLayout(const std::filesystem::path& root);

// The frames of the layout (layout "hdrgs-colmap"); images are not opened. Throws hdr4d::Error
// naming the file: no sparse model, a camera model with distortion, a view whose images are
// missing.
Dataset ReadHdrGsColmapLayout(const std::filesystem::path& root);

}  // namespace hdr4d
