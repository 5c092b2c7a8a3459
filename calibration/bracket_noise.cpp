#include "calibration/bracket_noise.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace hdr4d {
namespace {

using Histogram = std::array<double, kResponseCodes>;

Histogram CodeHistogram(const Image& image, int channel) {
  Histogram h{};
  const int channels = image.channels();
  for (std::size_t p = 0; p < image.num_pixels(); ++p) ++h[CodeOf(image.data()[p * channels + channel])];
  return h;
}

int Percentile(const Histogram& h, double fraction) {
  double total = 0;
  for (double v : h) total += v;
  double seen = 0;
  for (int z = 0; z < kResponseCodes; ++z) {
    seen += h[z];
    if (seen > fraction * total) return z;
  }
  return kResponseCodes - 1;
}

// A black floor is a peak: many pixels at the lowest codes, far more than just above them.
// A scene's own dark tail thins out slowly instead (no peak), and then black stays 0.
void FindFloor(const Histogram& h, double pixels, ChannelNoise* noise) {
  const int low = Percentile(h, 0.002);
  int mode = low;
  for (int z = low; z <= std::min(low + 24, kResponseCodes - 1); ++z)
    if (h[z] > h[mode]) mode = z;
  double above = 0;  // mean count a little above the peak
  for (int z = mode + 8; z < mode + 24 && z < kResponseCodes; ++z) above += h[z] / 16.0;
  if (h[mode] < 0.02 * pixels || h[mode] < 4 * std::max(above, 1.0)) return;
  // The spread below the peak is noise alone (light only adds); mirror it for sigma. Only the
  // ten codes below: far lower codes are something else (a scan's blank border, dead pixels).
  double sum = 0, count = 0;
  for (int z = std::max(mode - 10, mode >= 8 ? 1 : 0); z < mode; ++z)
    sum += h[z] * (z - mode) * (z - mode), count += h[z];
  noise->black = mode;
  noise->read_sigma = std::max(0.5, count > 0 ? std::sqrt(sum / count) : 0.5);
  noise->floor_found = true;
}

double Smoothstep(double a, double b, double x) {
  if (!(b > a)) return x >= b ? 1.0 : 0.0;
  const double t = std::clamp((x - a) / (b - a), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

}  // namespace

std::vector<ChannelNoise> EstimateBracketNoise(const std::vector<Bracket>& brackets) {
  std::vector<ChannelNoise> noise;
  if (brackets.empty()) return noise;
  std::size_t shortest = 0, longest = 0;
  for (std::size_t j = 0; j < brackets.size(); ++j) {
    if (brackets[j].exposure < brackets[shortest].exposure) shortest = j;
    if (brackets[j].exposure > brackets[longest].exposure) longest = j;
  }
  const double pixels = static_cast<double>(brackets[shortest].image.num_pixels());
  for (int c = 0; c < brackets.front().image.channels(); ++c) {
    ChannelNoise n;
    FindFloor(CodeHistogram(brackets[shortest].image, c), pixels, &n);
    // Saturation: a peak at the top codes of the longest bracket, or the code range's end.
    const Histogram top = CodeHistogram(brackets[longest].image, c);
    const int high = Percentile(top, 0.998);
    if (high < kResponseCodes - 1 && top[high] > 0.02 * pixels) n.saturation = high;
    noise.push_back(n);
  }
  return noise;
}

bool UsableCode(const ChannelNoise& noise, double value01) {
  const double z = std::clamp(value01, 0.0, 1.0) * (kResponseCodes - 1);
  return z > noise.black + 3 * noise.read_sigma && z < noise.saturation - 2;
}

double BracketWeight(const ChannelNoise& noise, const std::array<double, kResponseCodes>& inverse,
                     double value01, double exposure) {
  if (!(exposure > 0) || !std::isfinite(value01)) return 0;
  const double z = std::clamp(value01, 0.0, 1.0) * (kResponseCodes - 1);
  // Zero within three noise widths of black, full weight some codes later; the same towards
  // saturation, where the response flattens and clipped codes say only "at least".
  const double floor0 = noise.black + 3 * noise.read_sigma;
  const double low = Smoothstep(floor0, floor0 + 4 * noise.read_sigma + 4, z);
  const double high = 1 - Smoothstep(noise.saturation - 24, noise.saturation - 2, z);
  if (!(low * high > 0)) return 0;
  // x'(z) by central difference over two codes: the steeper the response, the more radiance
  // one code of noise is worth.
  const int zi = std::clamp(static_cast<int>(std::lround(z)), 2, kResponseCodes - 3);
  const double slope = (inverse[zi + 2] - inverse[zi - 2]) / 4;
  const double scale = std::max(inverse[zi], 1e-12);
  const double relative_slope = std::max(slope / scale, 1e-4);  // per code, relative to x
  // var(x/t) = (x' sigma / t)^2; relative to the estimate itself: (x'/x)^2 sigma^2. Using the
  // relative variance keeps weights comparable across brackets of very different radiance.
  const double variance = relative_slope * relative_slope *
                          (noise.read_sigma * noise.read_sigma + 1.0 / 12.0);
  return low * high / variance;
}

}  // namespace hdr4d
