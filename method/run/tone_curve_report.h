// The learned tone curves of a run (`hdr4d tone-curves`, the analysis of the paper's Fig. 3):
// for chosen times, each channel's LDR value as a function of x = log radiance + log exposure,
// with the context the tone mapper has for that time. Written as CSV and as a PNG (and SVG)
// chart with one panel per channel and one line per time.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "method/tonemap/tone_mapper.h"

namespace hdr4d::method {

struct ToneCurveSamples {
  std::vector<double> x;      // log radiance + log exposure
  std::vector<double> times;  // normalised times
  // ldr[t][c][i]: channel c at time t and x[i].
  std::vector<std::vector<std::vector<double>>> ldr;
};

// Samples a pointwise tone mapper (throws hdr4d::Error for a whole-image one) at `samples`
// values of x in [x_min, x_max] for each time. Leaves the mapper's radiance bank unchanged.
ToneCurveSamples SampleToneCurves(ToneMapper* tone_mapper,
                                  const std::vector<double>& times,
                                  int num_times,
                                  double x_min,
                                  double x_max,
                                  int samples);

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
