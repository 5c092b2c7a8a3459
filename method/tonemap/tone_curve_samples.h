// A pointwise tone mapper read as curves: each channel's LDR value as a function of
// x = log radiance + log exposure at chosen times, with the context the mapper has for that time.
// `hdr4d tone-curves` plots them (the analysis of the paper's Fig. 3); the trainer checks them
// for a curve that has gone flat (FindFlatToneCurves).
#pragma once

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

// A channel whose curve gives (nearly) one LDR value over a whole input range.
struct FlatToneCurve {
  int channel = 0;     // 0 red, 1 green, 2 blue
  double time = 0;     // normalised time of the first flat curve found
  double level = 0;    // its mean LDR value
  double spread = 0;   // max - min of its LDR values over the range
};

// The channels whose curve, at some time of 0, 1/2 and 1, varies by less than `tolerance` (LDR
// units) over [x_min, x_max], sampled at 64 points: one entry per such channel (its first flat
// time), in channel order; empty when every curve rises or falls by more, or when the mapper is
// not pointwise. Such a curve passes no gradient from an LDR loss to anything, itself included:
// the LDR images stay that colour for good.
std::vector<FlatToneCurve> FindFlatToneCurves(ToneMapper* tone_mapper,
                                              int num_times,
                                              double x_min,
                                              double x_max,
                                              double tolerance = 0.01);

}  // namespace hdr4d::method
