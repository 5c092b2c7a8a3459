// The learned tone curves of a run (`hdr4d tone-curves`, the analysis of the paper's Fig. 3):
// for chosen times, each channel's LDR value as a function of x = log radiance + log exposure,
// with the context the tone mapper has for that time. Written as CSV and as a PNG (and SVG)
// chart with one panel per channel and one line per time.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "method/tonemap/tone_curve_samples.h"

namespace hdr4d::method {

struct ToneCurvesOptions {
  std::filesystem::path run;
  std::filesystem::path out;  // default RUN/tone_curves
  std::vector<double> times = {0.0, 0.25, 0.5, 0.75, 1.0};
  double x_min = -12, x_max = 8;
  int samples = 256;
  std::string Validate() const;
};

// Writes OUT/tone_curves.csv, OUT/tone_curves.png and OUT/tone_curves.svg; returns the paths.
std::vector<std::filesystem::path> WriteToneCurves(const ToneCurvesOptions& options);

}  // namespace hdr4d::method
