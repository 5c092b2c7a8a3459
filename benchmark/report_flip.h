// The FLIP error maps of a scene's test view in the HTML report: per run, LDR-FLIP of its LDR
// render and HDR-FLIP of its HDR render against the ground truth (core/metrics/flip.h),
// coloured with magma as NVIDIA's FLIP tool shows them, with each map's mean.
#pragma once

#include <string>
#include <vector>

#include "benchmark/results_store.h"
#include "core/dataset/dataset.h"

namespace hdr4d::bench {

// A <p> and a table of maps for `view`; runs without a render of it get "-". Adds the pictures
// it embeds to *images.
std::string FlipMapsHtml(const Frame& view, const std::vector<const RunSummary*>& runs,
                         int* images);

}  // namespace hdr4d::bench
