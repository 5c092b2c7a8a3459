#include "core/radiometry/camera_pipeline_rig_mismatch.h"

#include <cmath>
#include <random>

namespace hdr4d {
namespace {

std::uint64_t SplitMix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace

RigCameraDifference DrawRigCamera(std::uint64_t seed, int camera, bool reference, double gain,
                                  double response, double colour) {
  RigCameraDifference d;
  if (reference) return d;
  std::mt19937_64 rng(SplitMix(SplitMix(seed ^ 0x7269672d6d69736dULL) ^  // "rig-mism"
                               static_cast<std::uint64_t>(camera)));
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  d.gain = std::exp(gain * unit(rng));
  d.exponent = 1.0 + response * unit(rng);
  std::array<double, 3> channel;
  for (double& c : channel) c = std::exp(colour * unit(rng));
  for (int r = 0; r < 3; ++r) {
    double off_sum = 0;
    for (int c = 0; c < 3; ++c) {
      if (c == r) continue;
      const double v = colour * unit(rng);
      d.colour[r * 3 + c] = v;
      off_sum += v;
    }
    d.colour[r * 3 + r] = 1.0 - off_sum;
    for (int c = 0; c < 3; ++c) d.colour[r * 3 + c] *= channel[r];
  }
  return d;
}

}  // namespace hdr4d
