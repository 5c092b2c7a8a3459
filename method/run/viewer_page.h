// `hdr4d view`: a trained run as one self-contained HTML page (no network: script, style and data
// inline) that renders its Gaussians with WebGL 2 (viewer/ holds the page's code, embedded at
// build time). The data: the 4D model as a 4D .ply (gaussian_4d_ply.h) and a JSON block with the
// dataset's cameras, the time and exposure ranges, the background and, for a pointwise tone
// mapper, its curves baked over a grid of times and exposures (tone_tables.h). docs/viewer.md
// says what the page shows and how close it is to `hdr4d render`.
#pragma once

#include <filesystem>
#include <string>

#include "method/run/render_split.h"

namespace hdr4d::method {

struct ViewerPageOptions {
  int tone_nodes = 512;     // log-HDR nodes of each baked curve
  int max_time_rows = 64;   // radiance-bank rows baked (nearest row between them)
  int exposure_steps = 17;  // exposures baked, log-spaced over the slider's range
  std::string title;        // default: the run folder's name
};

// The page. Throws hdr4d::Error when the model has no 3 colour channels.
std::string ViewerPageHtml(const LoadedRun& run, const ViewerPageOptions& options);

// What the page's LDR mode shows for this run, in words (also printed by `hdr4d view`).
std::string ViewerLdrNote(const LoadedRun& run);

}  // namespace hdr4d::method
