#include "calibration/hdr_fusion.h"

#include <algorithm>
#include <cmath>

#include "core/util/error.h"

namespace hdr4d {
namespace {

// Codes within this margin of black or white do not count as well exposed.
constexpr int kWellExposedMargin = 12;

double FusionWeight(int code) {
  return std::max(0, std::min(code, kResponseCodes - 1 - code)) / 127.5;
}

bool WellExposed(int code) {
  return code >= kWellExposedMargin && code <= kResponseCodes - 1 - kWellExposedMargin;
}

// Codes whose radiance estimate is trusted enough to call a disagreement motion: recovered
// responses are steep and noisy in the darkest eighth.
constexpr int kReliableMargin = 32;
bool Reliable(int code) { return code >= kReliableMargin && code <= kResponseCodes - 1 - kReliableMargin; }

}  // namespace

FusionResult FuseBrackets(const std::vector<Bracket>& brackets,
                          const CameraResponse& response,
                          const FusionOptions& options) {
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
  const int w = first.width(), h = first.height(), channels = first.channels();
  const std::size_t n = first.num_pixels();
  const int nb = static_cast<int>(brackets.size());

  // Code of each bracket at each pixel (the mean over channels decides exposure quality).
  auto mean_code = [&](int j, std::size_t p) {
    double sum = 0;
    for (int c = 0; c < channels; ++c) sum += brackets[j].image.data()[p * channels + c];
    return CodeOf(static_cast<float>(sum / channels));
  };
  FusionResult result;
  int best_count = -1;
  for (int j = 0; j < nb; ++j) {
    int count = 0;
    for (std::size_t p = 0; p < n; ++p) {
      bool reliable = true;
      for (int c = 0; c < channels; ++c) reliable &= Reliable(CodeOf(brackets[j].image.data()[p * channels + c]));
      count += reliable;
    }
    if (count > best_count) best_count = count, result.reference_bracket = j;
  }
  const int ref = result.reference_bracket;

  // How much one code step changes log exposure at a value: where the response is steep (dark
  // codes), quantisation alone makes brackets disagree by this much, which is no motion.
  auto log_step = [&](int c, float value) {
    const int z = std::clamp(CodeOf(value), 1, kResponseCodes - 2);
    const auto& x = response.inverse[std::min<std::size_t>(c, response.inverse.size() - 1)];
    return x[z - 1] > 0 ? 0.5 * std::log(x[z + 1] / x[z - 1]) : 0.0;
  };
  auto radiance = [&](int j, std::size_t p, int c) {
    return response.Linearize(c, brackets[j].image.data()[p * channels + c]) / brackets[j].exposure;
  };

  std::vector<std::uint8_t> moving(n, 0);
  if (options.detect_motion && nb > 1) {
    for (std::size_t p = 0; p < n; ++p) {
      for (int j = 0; j < nb && !moving[p]; ++j) {
        if (j == ref) continue;
        for (int c = 0; c < channels; ++c) {
          if (!Reliable(CodeOf(brackets[ref].image.data()[p * channels + c])) ||
              !Reliable(CodeOf(brackets[j].image.data()[p * channels + c])))
            continue;
          const double a = radiance(ref, p, c), b = radiance(j, p, c);
          const double tolerance = options.motion_log_threshold +
                                   2 * (log_step(c, brackets[ref].image.data()[p * channels + c]) +
                                        log_step(c, brackets[j].image.data()[p * channels + c]));
          if (a > 0 && b > 0 && std::abs(std::log(a / b)) > tolerance) {
            moving[p] = 1;
            break;
          }
        }
      }
    }
    // Noise and grain flag scattered single pixels; a moving object flags a region. Keep a
    // flag only where most of its 3x3 neighbourhood agrees, then dilate so the blurred border
    // of the object is covered too.
    auto neighbours = [&](const std::vector<std::uint8_t>& mask, int x, int y) {
      int count = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = std::clamp(x + dx, 0, w - 1), yy = std::clamp(y + dy, 0, h - 1);
          count += mask[static_cast<std::size_t>(yy) * w + xx];
        }
      return count;
    };
    std::vector<std::uint8_t> kept(n, 0);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        kept[static_cast<std::size_t>(y) * w + x] = moving[static_cast<std::size_t>(y) * w + x] && neighbours(moving, x, y) >= 5;
    moving.swap(kept);
    for (int pass = 0; pass < options.motion_dilation; ++pass) {
      std::vector<std::uint8_t> grown(n, 0);
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) grown[static_cast<std::size_t>(y) * w + x] = neighbours(moving, x, y) > 0;
      moving.swap(grown);
    }
  }

  result.hdr = Image(w, h, channels, Encoding::kLinear);
  std::size_t moving_count = 0;
  std::vector<float> luminance(n);
  for (std::size_t p = 0; p < n; ++p) {
    // The bracket a moving pixel falls back to: the reference unless it is clipped there.
    int only = -1;
    if (moving[p]) {
      ++moving_count;
      only = ref;
      if (!WellExposed(mean_code(ref, p))) {
        double best = -1;
        for (int j = 0; j < nb; ++j)
          if (FusionWeight(mean_code(j, p)) > best) best = FusionWeight(mean_code(j, p)), only = j;
      }
    }
    double lum = 0;
    for (int c = 0; c < channels; ++c) {
      double num = 0, den = 0;
      for (int j = 0; j < nb; ++j) {
        if (only >= 0 && j != only) continue;
        const double wgt = FusionWeight(CodeOf(brackets[j].image.data()[p * channels + c]));
        num += wgt * radiance(j, p, c);
        den += wgt;
      }
      double value;
      if (den > 0) {
        value = num / den;
      } else {
        // Clipped in every bracket used: the shortest exposure bounds a bright pixel, the
        // longest a dark one.
        int pick = 0;
        const bool bright = brackets[only >= 0 ? only : 0].image.data()[p * channels + c] > 0.5f;
        for (int j = 0; j < nb; ++j) {
          if (only >= 0) { pick = only; break; }
          if (bright ? brackets[j].exposure < brackets[pick].exposure
                     : brackets[j].exposure > brackets[pick].exposure)
            pick = j;
        }
        value = radiance(pick, p, c);
      }
      result.hdr.data()[p * channels + c] = static_cast<float>(value);
      lum += value;
    }
    luminance[p] = static_cast<float>(lum / channels);
  }
  result.motion_fraction = n > 0 ? static_cast<double>(moving_count) / n : 0;
  std::sort(luminance.begin(), luminance.end());
  const float lo = std::max(luminance[static_cast<std::size_t>(0.001 * (n - 1))], 1e-12f);
  const float hi = std::max(luminance[static_cast<std::size_t>(0.999 * (n - 1))], lo);
  result.dynamic_range_stops = std::log2(hi / lo);
  return result;
}

}  // namespace hdr4d
