// Per-scene sections of the HTML report (benchmark/report.h) and the HTML helpers they share.
#pragma once

#include <string>
#include <vector>

#include "benchmark/results_store.h"
#include "benchmark/suite.h"

namespace hdr4d::bench {

std::string HtmlEscape(const std::string& text);
// <img> with a data URI; width 0 keeps the image's own.
std::string HtmlImg(const std::string& uri, const std::string& alt, int width = 0);

// The runs shown for a scene: one per (method, supervision) in table-row order, lowest seed.
std::vector<const RunSummary*> SceneRuns(const std::vector<RunSummary>& runs, const Suite& suite,
                                         const std::string& scene, const std::string& budget,
                                         const std::string& variant);

// A scene's section: renders beside the ground truth with error maps, region luminance over
// time, learned tone curves over time, training curves. Adds the pictures it embeds to *images.
std::string SceneHtml(const std::string& scene, const std::vector<const RunSummary*>& runs,
                      const ResultsStore& store, int* images);

}  // namespace hdr4d::bench
