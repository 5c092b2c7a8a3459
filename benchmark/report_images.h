// Pictures for the HTML report, as data URIs so the page is one self-contained file: renders
// and ground truth as PNG, HDR images through the mu-law of the metrics (each image over its
// own maximum, as the HDR-4DGS protocol scores them), error maps with a fixed colour scale,
// and charts from core's plot library as SVG.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/viz/plot.h"

namespace hdr4d::bench {

std::string Base64(const std::string& bytes);
// "data:image/png;base64,..." of an image (written as 8-bit PNG; values clamped to [0,1]).
std::string PngDataUri(const Image& image);
// The file's bytes as a data URI (PNG or SVG by extension).
std::string FileDataUri(const std::filesystem::path& path);
std::string SvgDataUri(const std::string& svg);
std::string PlotDataUri(const std::vector<PlotSeries>& series, const PlotOptions& options);
std::string PlotGridDataUri(const std::vector<PlotPanel>& panels, int columns);

// An HDR image as the metrics see it: divided by its maximum, clamped, mu-law (mu = 5000).
Image MuLawDisplay(const Image& hdr);
// |a - b| averaged over the RGB channels, through a black-red-yellow-white ramp where white is
// `full_scale` (values above are white).
Image ErrorMap(const Image& a, const Image& b, double full_scale);
// A copy with a 1-pixel rectangle (fractions x, y, w, h) drawn in `rgb`.
Image WithBox(const Image& image, const std::array<double, 4>& box, const std::array<float, 3>& rgb);

}  // namespace hdr4d::bench
