#include "calibration/hdr_fusion.h"

#include <algorithm>
#include <cmath>

#include "core/util/error.h"

namespace hdr4d {
namespace {

// Codes whose radiance estimate is trusted enough to call a disagreement motion: recovered
// responses are steep and noisy in the darkest eighth.
constexpr int kReliableMargin = 32;
bool Reliable(int code) { return code >= kReliableMargin && code <= kResponseCodes - 1 - kReliableMargin; }

void CheckBrackets(const std::vector<Bracket>& brackets, const CameraResponse& response) {
  if (brackets.empty()) Fail("HDR fusion: no brackets");
  if (response.inverse.empty()) Fail("HDR fusion: the response has no channels");
  const Image& first = brackets.front().image;
  for (const Bracket& b : brackets) {
    if (!b.image.SameShape(first))
      Fail("{}: size {} differs from {} ({})", b.name, b.image.ShapeString(), brackets.front().name,
           first.ShapeString());
    if (!(b.exposure > 0) || !std::isfinite(b.exposure))
      Fail("{}: exposure time {} is not a positive number", b.name, b.exposure);
  }
}

// Everything the per-pixel steps share.
struct Stack {
  const std::vector<Bracket>& brackets;
  const CameraResponse& response;
  const std::vector<ChannelNoise>& noise;
  int w, h, channels;
  std::size_t n;
  float value(int j, std::size_t p, int c) const { return brackets[j].image.data()[p * channels + c]; }
  const std::array<double, kResponseCodes>& inverse(int c) const {
    return response.inverse[std::min<std::size_t>(c, response.inverse.size() - 1)];
  }
  const ChannelNoise& noise_of(int c) const { return noise[std::min<std::size_t>(c, noise.size() - 1)]; }
  double radiance(int j, std::size_t p, int c) const {
    return response.Linearize(c, value(j, p, c)) / brackets[j].exposure;
  }
  double weight(int j, std::size_t p, int c) const {
    return BracketWeight(noise_of(c), inverse(c), value(j, p, c), brackets[j].exposure);
  }
  // The bracket's weight at a pixel: its worst channel's, since one clipped channel spoils
  // the colour.
  double pixel_weight(int j, std::size_t p) const {
    double wmin = 1e300;
    for (int c = 0; c < channels; ++c) wmin = std::min(wmin, weight(j, p, c));
    return wmin;
  }
};

// The best-exposed bracket overall: the most pixels reliable in every channel.
int PickReference(const Stack& s) {
  int best = 0, best_count = -1;
  for (int j = 0; j < static_cast<int>(s.brackets.size()); ++j) {
    int count = 0;
    for (std::size_t p = 0; p < s.n; ++p) {
      bool reliable = true;
      for (int c = 0; c < s.channels; ++c) reliable &= Reliable(CodeOf(s.value(j, p, c)));
      count += reliable;
    }
    if (count > best_count) best_count = count, best = j;
  }
  return best;
}

// How much one code step changes log exposure at a value: where the response is steep (dark
// codes), quantisation alone makes brackets disagree by this much, which is no motion.
double LogStep(const Stack& s, int c, float value) {
  const int z = std::clamp(CodeOf(value), 1, kResponseCodes - 2);
  const auto& x = s.inverse(c);
  return x[z - 1] > 0 ? 0.5 * std::log(x[z + 1] / x[z - 1]) : 0.0;
}

bool Disagrees(const Stack& s, const FusionOptions& options, int ref, int j, std::size_t p) {
  for (int c = 0; c < s.channels; ++c) {
    if (!Reliable(CodeOf(s.value(ref, p, c))) || !Reliable(CodeOf(s.value(j, p, c)))) continue;
    const double a = s.radiance(ref, p, c), b = s.radiance(j, p, c);
    const double tolerance = options.motion_log_threshold +
                             2 * (LogStep(s, c, s.value(ref, p, c)) + LogStep(s, c, s.value(j, p, c)));
    if (a > 0 && b > 0 && std::abs(std::log(a / b)) > tolerance) return true;
  }
  return false;
}

int Neighbours(const std::vector<std::uint8_t>& mask, int w, int h, int x, int y) {
  int count = 0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      const int xx = std::clamp(x + dx, 0, w - 1), yy = std::clamp(y + dy, 0, h - 1);
      count += mask[static_cast<std::size_t>(yy) * w + xx];
    }
  return count;
}

// Noise and grain flag scattered single pixels; a moving object flags a region. Keep a flag
// only where most of its 3x3 neighbourhood agrees, then dilate so the blurred border of the
// object is covered too.
void CleanMotionMask(int w, int h, int dilation, std::vector<std::uint8_t>* moving) {
  const std::size_t n = moving->size();
  std::vector<std::uint8_t> kept(n, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      kept[i] = (*moving)[i] && Neighbours(*moving, w, h, x, y) >= 5;
    }
  moving->swap(kept);
  for (int pass = 0; pass < dilation; ++pass) {
    std::vector<std::uint8_t> grown(n, 0);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) grown[static_cast<std::size_t>(y) * w + x] = Neighbours(*moving, w, h, x, y) > 0;
    moving->swap(grown);
  }
}

std::vector<std::uint8_t> DetectMotion(const Stack& s, const FusionOptions& options, int ref) {
  std::vector<std::uint8_t> moving(s.n, 0);
  const int nb = static_cast<int>(s.brackets.size());
  if (!options.detect_motion || nb < 2) return moving;
  for (std::size_t p = 0; p < s.n; ++p)
    for (int j = 0; j < nb && !moving[p]; ++j)
      if (j != ref && Disagrees(s, options, ref, j, p)) moving[p] = 1;
  CleanMotionMask(s.w, s.h, options.motion_dilation, &moving);
  return moving;
}

// The one bracket a moving pixel falls back to: the reference unless it is unusable there,
// then the bracket that weighs most.
int FallbackBracket(const Stack& s, int ref, std::size_t p) {
  if (s.pixel_weight(ref, p) > 0) return ref;
  int only = ref;
  double best = 0;
  for (int j = 0; j < static_cast<int>(s.brackets.size()); ++j)
    if (const double wj = s.pixel_weight(j, p); wj > best) best = wj, only = j;
  return only;
}

// No bracket usable in this channel: the shortest exposure bounds a bright pixel, the longest
// a dark one.
double ClippedValue(const Stack& s, std::size_t p, int c, int only) {
  if (only >= 0) return s.radiance(only, p, c);
  const bool bright = s.value(0, p, c) > 0.5f;
  int pick = 0;
  for (int j = 0; j < static_cast<int>(s.brackets.size()); ++j)
    if (bright ? s.brackets[j].exposure < s.brackets[pick].exposure
               : s.brackets[j].exposure > s.brackets[pick].exposure)
      pick = j;
  return s.radiance(pick, p, c);
}

double FuseChannel(const Stack& s, std::size_t p, int c, int only) {
  double num = 0, den = 0;
  for (int j = 0; j < static_cast<int>(s.brackets.size()); ++j) {
    if (only >= 0 && j != only) continue;
    const double wgt = s.weight(j, p, c);
    num += wgt * s.radiance(j, p, c);
    den += wgt;
  }
  return den > 0 ? num / den : ClippedValue(s, p, c, only);
}

double DynamicRangeStops(std::vector<float> luminance) {
  if (luminance.empty()) return 0;
  std::sort(luminance.begin(), luminance.end());
  const std::size_t n = luminance.size();
  const float lo = std::max(luminance[static_cast<std::size_t>(0.001 * (n - 1))], 1e-12f);
  const float hi = std::max(luminance[static_cast<std::size_t>(0.999 * (n - 1))], lo);
  return std::log2(hi / lo);
}

}  // namespace

FusionResult FuseBrackets(const std::vector<Bracket>& brackets,
                          const CameraResponse& response,
                          const FusionOptions& options) {
  CheckBrackets(brackets, response);
  FusionResult result;
  result.noise = EstimateBracketNoise(brackets);
  const Image& first = brackets.front().image;
  const Stack s{brackets, response, result.noise, first.width(), first.height(), first.channels(),
                first.num_pixels()};
  result.reference_bracket = PickReference(s);
  const std::vector<std::uint8_t> moving = DetectMotion(s, options, result.reference_bracket);

  result.hdr = Image(s.w, s.h, s.channels, Encoding::kLinear);
  std::size_t moving_count = 0;
  std::vector<float> luminance(s.n);
  for (std::size_t p = 0; p < s.n; ++p) {
    const int only = moving[p] ? FallbackBracket(s, result.reference_bracket, p) : -1;
    moving_count += moving[p];
    double lum = 0;
    for (int c = 0; c < s.channels; ++c) {
      const double value = FuseChannel(s, p, c, only);
      result.hdr.data()[p * s.channels + c] = static_cast<float>(value);
      lum += value;
    }
    luminance[p] = static_cast<float>(lum / s.channels);
  }
  result.motion_fraction = s.n > 0 ? static_cast<double>(moving_count) / s.n : 0;
  result.dynamic_range_stops = DynamicRangeStops(std::move(luminance));
  return result;
}

}  // namespace hdr4d
