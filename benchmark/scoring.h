// Scoring a folder of renders against a dataset split with core's evaluation (the same code as
// `hdr4d eval`): every LDR ground-truth image and every HDR ground-truth image of the split is
// one scored frame (a render with three exposures has three LDR frames and one HDR frame, as
// `hdr4d eval` pairs files), with the region luminance the report plots over time.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "benchmark/run_record.h"
#include "core/dataset/dataset.h"

namespace hdr4d::bench {

struct ScoringOptions {
  Split split = Split::kTest;
  // Submissions: every render of a kind (LDR or HDR) the folder has must be there, and no
  // other image may be. Harness renders: a kind the method does not output is simply absent.
  bool strict = false;
  // Region (fractions x, y, w, h) for the luminance over time; unset: chosen from the ground
  // truth (RegionFromGroundTruth).
  std::optional<std::array<double, 4>> region;
};

struct ScoredRenders {
  std::vector<FrameResult> frames;
  std::array<double, 4> region{};  // the region used, as fractions
  int region_camera = -1;          // the camera whose views the report plots over time
};

// The file names a render of `frame` has (what `hdr4d render` writes).
std::string LdrRenderName(const Frame& frame);
std::string HdrRenderName(const Frame& frame);

// Throws hdr4d::Error naming the file for a missing render (strict, or a kind with some but
// not all renders), an extra image (strict), a size mismatch, a NaN/Inf pixel or an unreadable
// image; nothing is half-scored.
ScoredRenders ScoreRenders(const Dataset& dataset,
                           const std::filesystem::path& renders,
                           const ScoringOptions& options);

// The cell of an 8 x 8 grid whose mean log luminance varies most over time in the ground truth
// of one camera's views of the split (HDR where there is HDR ground truth, else LDR): the
// region where a tone mapper has to follow the scene's changing radiance.
std::array<double, 4> RegionFromGroundTruth(const Dataset& dataset, Split split, int camera);

}  // namespace hdr4d::bench
