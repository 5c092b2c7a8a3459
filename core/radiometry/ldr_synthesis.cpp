#include "core/radiometry/ldr_synthesis.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "core/util/error.h"
#include "core/util/parallel.h"

namespace hdr4d {
namespace {

constexpr std::int64_t kPixelGrain = 2048;
// Below this mean electron count the Poisson law is sampled exactly; above it the Gaussian
// approximation's skew (1 / sqrt(mean) < 0.23) no longer matters for a synthetic sensor.
constexpr double kExactPoissonMaxMean = 20.0;

// SplitMix64's output function: a bijection on 64 bits with full avalanche.
inline std::uint64_t Mix(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// Counter-based random numbers: draw j of value `index` depends only on (seed, index, j), so a
// parallel loop produces the same values in any order and at any thread count.
class ValueRng {
 public:
  ValueRng(std::uint64_t seed_key, std::uint64_t index) : key_(Mix(seed_key ^ index)) {}
  // Uniform in the open interval (0, 1).
  double Uniform(std::uint64_t draw) const {
    return (static_cast<double>(Mix(key_ + draw) >> 11) + 0.5) * 0x1p-53;
  }
  // Two independent standard normals (Box-Muller on draws 0 and 1).
  void Normals(double& z0, double& z1) const {
    const double r = std::sqrt(-2.0 * std::log(Uniform(0)));
    const double phi = 2.0 * std::numbers::pi * Uniform(1);
    z0 = r * std::cos(phi);
    z1 = r * std::sin(phi);
  }
  // Poisson(mean) by inversion of the CDF with draw 2; mean <= kExactPoissonMaxMean.
  double Poisson(double mean) const {
    const double u = Uniform(2);
    double p = std::exp(-mean), cdf = p;
    int k = 0;
    while (u > cdf && k < 1000) {
      ++k;
      p *= mean / k;
      cdf += p;
    }
    return k;
  }

 private:
  std::uint64_t key_;
};

int ColourChannels(const Image& image) { return image.ColourChannelCount(); }

void CheckExposure(const char* what, double exposure) {
  if (!std::isfinite(exposure) || !(exposure > 0)) {
    Fail("{}: exposure time must be a finite number of seconds > 0, got {}", what, exposure);
  }
}

// Display-encoded input: tagged sRGB, every value in [0,1]. `what` names the image.
void CheckLdr(const std::string& what, const Image& ldr) {
  if (ldr.empty()) Fail("{}: the image is empty ({})", what, ldr.ShapeString());
  if (ldr.encoding() != Encoding::kSrgb) {
    Fail(
        "{}: expected display-encoded values (sRGB-tagged, as read from PNG/JPEG), got a "
        "linear image ({}); it may have been linearised already",
        what, ldr.ShapeString());
  }
  const std::vector<float>& v = ldr.values();
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!(v[i] >= 0.0f && v[i] <= 1.0f)) {
      const std::size_t pixel = i / ldr.channels();
      Fail("{}: value {} at pixel ({}, {}) channel {} is outside [0, 1] (image {})", what, v[i],
           pixel % ldr.width(), pixel / ldr.width(), i % ldr.channels(), ldr.ShapeString());
    }
  }
}

void CheckInvertible(const char* what, const Crf& crf) {
  if (!crf.Invertible()) {
    Fail(
        "{}: the camera response '{}' is not invertible (a flat piece between black and "
        "white maps many exposures to one value)",
        what, crf.Spec());
  }
}

}  // namespace

void LdrSynthesisOptions::Validate() const {
  CheckExposure("LDR synthesis", exposure);
  if (bits != 0 && bits != 8 && bits != 16) {
    Fail("LDR synthesis: bits must be 8, 16 or 0 (no quantisation), got {}", bits);
  }
  if (!std::isfinite(noise.full_well) || noise.full_well < 0) {
    Fail(
        "LDR synthesis: full_well must be a finite electron count >= 0 (0 = no shot noise), "
        "got {}",
        noise.full_well);
  }
  if (!std::isfinite(noise.read_sigma) || noise.read_sigma < 0) {
    Fail("LDR synthesis: read_sigma must be a finite number >= 0 (0 = no read noise), got {}",
         noise.read_sigma);
  }
}

Image SynthesizeLdr(const Image& hdr, const Crf& crf, const LdrSynthesisOptions& options) {
  options.Validate();
  if (hdr.empty()) Fail("LDR synthesis: the HDR image is empty ({})", hdr.ShapeString());
  if (hdr.encoding() != Encoding::kLinear) {
    Fail("LDR synthesis: expected linear HDR radiance, got a display-encoded (sRGB) image ({})",
         hdr.ShapeString());
  }
  const std::vector<float>& in = hdr.values();
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (!std::isfinite(in[i]) || in[i] < 0.0f) {
      const std::size_t pixel = i / hdr.channels();
      Fail(
          "LDR synthesis: HDR value {} at pixel ({}, {}) channel {} is not a radiance; values "
          "must be finite and >= 0 (image {})",
          in[i], pixel % hdr.width(), pixel / hdr.width(), i % hdr.channels(), hdr.ShapeString());
    }
  }

  const int channels = hdr.channels();
  const int colour = ColourChannels(hdr);
  const double exposure = options.exposure;
  const double full_well = options.noise.full_well;
  const double read_sigma = options.noise.read_sigma;
  const bool noisy = full_well > 0 || read_sigma > 0;
  const std::uint64_t seed_key = Mix(options.noise.seed);
  const double levels = options.bits == 0 ? 0.0 : std::ldexp(1.0, options.bits) - 1.0;
  const auto finish = [levels](double y) {
    y = std::clamp(y, 0.0, 1.0);
    return static_cast<float>(levels > 0 ? std::round(y * levels) / levels : y);
  };

  Image out(hdr.width(), hdr.height(), channels, Encoding::kSrgb);
  float* dst = out.data();
  ParallelFor(static_cast<std::int64_t>(hdr.num_pixels()), kPixelGrain, [&](std::int64_t p) {
    for (int c = 0; c < channels; ++c) {
      const std::size_t i = static_cast<std::size_t>(p) * channels + c;
      if (c >= colour) {  // alpha
        dst[i] = finish(in[i]);
        continue;
      }
      double x = static_cast<double>(in[i]) * exposure;
      if (noisy) {
        const ValueRng rng(seed_key, i);
        double z_shot = 0, z_read = 0;
        rng.Normals(z_shot, z_read);
        const double electrons = x * full_well;
        if (full_well > 0 && std::isfinite(electrons)) {
          const double noisy_electrons = electrons <= kExactPoissonMaxMean
                                             ? rng.Poisson(electrons)
                                             : electrons + std::sqrt(electrons) * z_shot;
          x = noisy_electrons / full_well;
        }
        x += read_sigma * z_read;
      }
      dst[i] = finish(crf.Apply(std::max(x, 0.0)));
    }
  });
  return out;
}

Image LinearizeLdr(const Image& ldr, const Crf& crf, double exposure) {
  CheckExposure("LDR linearisation", exposure);
  CheckLdr("LDR linearisation", ldr);
  CheckInvertible("LDR linearisation", crf);
  const int channels = ldr.channels();
  const int colour = ColourChannels(ldr);
  Image out(ldr.width(), ldr.height(), channels, Encoding::kLinear);
  const float* src = ldr.data();
  float* dst = out.data();
  ParallelFor(static_cast<std::int64_t>(ldr.num_pixels()), kPixelGrain, [&](std::int64_t p) {
    for (int c = 0; c < channels; ++c) {
      const std::size_t i = static_cast<std::size_t>(p) * channels + c;
      dst[i] = c < colour ? static_cast<float>(crf.Inverse(src[i]) / exposure) : src[i];
    }
  });
  return out;
}

Image MergeExposures(const std::vector<Image>& ldr_stack,
                     const std::vector<double>& exposures,
                     const Crf& crf) {
  const char* what = "HDR merge";
  if (ldr_stack.empty()) Fail("{}: no images to merge", what);
  if (exposures.size() != ldr_stack.size()) {
    Fail("{}: {} images but {} exposure times", what, ldr_stack.size(), exposures.size());
  }
  for (std::size_t j = 0; j < ldr_stack.size(); ++j) {
    const std::string name = fmt::format("{}: image {} (exposure {} s)", what, j, exposures[j]);
    CheckExposure(name.c_str(), exposures[j]);
    if (!ldr_stack[j].SameShape(ldr_stack[0])) {
      Fail("{}: image {} is {} but image 0 is {}; a bracket must share one shape", what, j,
           ldr_stack[j].ShapeString(), ldr_stack[0].ShapeString());
    }
    CheckLdr(name, ldr_stack[j]);
  }
  CheckInvertible(what, crf);

  const std::size_t n = ldr_stack.size();
  const Image& first = ldr_stack[0];
  const int channels = first.channels();
  const int colour = ColourChannels(first);
  // Exposure indices from shortest to longest.
  std::vector<std::size_t> order(n);
  for (std::size_t j = 0; j < n; ++j) order[j] = j;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return exposures[a] < exposures[b]; });
  const double saturation = crf.Saturation();

  Image out(first.width(), first.height(), channels, Encoding::kLinear);
  float* dst = out.data();
  ParallelFor(static_cast<std::int64_t>(first.num_pixels()), kPixelGrain, [&](std::int64_t p) {
    for (int c = 0; c < channels; ++c) {
      const std::size_t i = static_cast<std::size_t>(p) * channels + c;
      if (c >= colour) {  // alpha: the mean over the stack
        double sum = 0;
        for (const Image& image : ldr_stack) sum += image.values()[i];
        dst[i] = static_cast<float>(sum / n);
        continue;
      }
      double weight_sum = 0, log_sum = 0;
      for (std::size_t j = 0; j < n; ++j) {
        const double y = ldr_stack[j].values()[i];
        const double w = std::min(y, 1.0 - y);
        if (!(w > 0)) continue;
        const double x = crf.Inverse(y);
        if (!(x > 0)) continue;  // underflow of a very steep inverse: treat as black
        weight_sum += w;
        log_sum += w * std::log(x / exposures[j]);
      }
      double radiance;
      if (weight_sum > 0) {
        radiance = std::exp(log_sum / weight_sum);
      } else {
        // No vote. A clipped value bounds the radiance from below by saturation / t; the
        // shortest clipped exposure gives the tightest bound. All black: the longest's estimate.
        radiance = -1;
        for (std::size_t j : order) {
          if (ldr_stack[j].values()[i] >= 1.0f) {
            radiance = saturation / exposures[j];
            break;
          }
        }
        if (radiance < 0) {
          const std::size_t longest = order.back();
          radiance = crf.Inverse(ldr_stack[longest].values()[i]) / exposures[longest];
        }
      }
      dst[i] = static_cast<float>(radiance);
    }
  });
  return out;
}

}  // namespace hdr4d
