#include "datagen/capture_lens.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/util/error.h"

namespace hdr4d::datagen {
namespace {

// Bilinear sample at continuous pixel coordinates (pixel i's centre at i + 0.5), edges clamped.
float Bilinear(const Image& img, double u, double v, int c) {
  const double x = std::clamp(u - 0.5, 0.0, img.width() - 1.0);
  const double y = std::clamp(v - 0.5, 0.0, img.height() - 1.0);
  const int x0 = std::min(static_cast<int>(x), img.width() - 1), y0 = std::min(static_cast<int>(y), img.height() - 1);
  const int x1 = std::min(x0 + 1, img.width() - 1), y1 = std::min(y0 + 1, img.height() - 1);
  const double fx = x - x0, fy = y - y0;
  const double top = (1 - fx) * img.at(x0, y0, c) + fx * img.at(x1, y0, c);
  const double bottom = (1 - fx) * img.at(x0, y1, c) + fx * img.at(x1, y1, c);
  return static_cast<float>((1 - fy) * top + fy * bottom);
}

// The undistorted normalised point whose distortion is (xd, yd).
void Undistort(const CaptureLens& lens, double xd, double yd, double* xu, double* yu) {
  *xu = xd;
  *yu = yd;
  for (int i = 0; i < 30; ++i) {  // a contraction for the gentle lenses drawn here
    const double r2 = *xu * *xu + *yu * *yu;
    const double d = 1 + lens.k1 * r2 + lens.k2 * r2 * r2;
    if (!(d > 0.1)) break;  // guard: far outside the drawn lenses' range
    *xu = xd / d;
    *yu = yd / d;
  }
}

}  // namespace

std::vector<CaptureLens> DrawCaptureLenses(const std::string& mode, std::uint64_t seed, int count) {
  if (mode != "none" && mode != "distortion" && mode != "vignetting" && mode != "both")
    Fail("datagen: --lenses {}: use none, distortion, vignetting or both", mode);
  const bool distortion = mode == "distortion" || mode == "both";
  const bool vignetting = mode == "vignetting" || mode == "both";
  std::mt19937_64 rng(seed ^ 0x6c656e736573ULL);  // "lenses"
  std::uniform_real_distribution<double> k1(0.03, 0.10), k2(0.0, 0.03), vig(0.05, 0.25);
  std::vector<CaptureLens> lenses;
  for (int c = 0; c < count; ++c) {
    const double a = k1(rng), b = k2(rng), v = vig(rng);
    CaptureLens lens;
    if (distortion) {
      lens.k1 = a;
      lens.k2 = b;
    }
    if (vignetting) lens.vignetting = v;
    lenses.push_back(lens);
  }
  return lenses;
}

Image ApplyCaptureLens(const Image& hdr, const CaptureLens& lens, const PinholeIntrinsics& k) {
  if (lens.Identity()) return hdr;
  HDR4D_CHECK(k.fx > 0 && k.fy > 0);
  Image out(hdr.width(), hdr.height(), hdr.channels(), hdr.encoding());
  const double corner2 = std::max({k.cx * k.cx + k.cy * k.cy,
                                   std::pow(hdr.width() - k.cx, 2) + std::pow(hdr.height() - k.cy, 2), 1.0});
  for (int y = 0; y < hdr.height(); ++y) {
    for (int x = 0; x < hdr.width(); ++x) {
      const double u = x + 0.5, v = y + 0.5;
      double xu = 0, yu = 0;
      Undistort(lens, (u - k.cx) / k.fx, (v - k.cy) / k.fy, &xu, &yu);
      const double r2 = ((u - k.cx) * (u - k.cx) + (v - k.cy) * (v - k.cy)) / corner2;
      const double fall = std::max(0.0, 1 - lens.vignetting * r2);
      for (int c = 0; c < hdr.channels(); ++c)
        out.at(x, y, c) = static_cast<float>(fall * Bilinear(hdr, xu * k.fx + k.cx, yu * k.fy + k.cy, c));
    }
  }
  return out;
}

Image ApplyBlackLevel(const Image& display, double black, double noise, std::uint64_t seed) {
  if (!(black >= 0 && black < 128))
    Fail("datagen: black level {} codes: use 0 to 127", black);
  if (!(noise >= 0) || !std::isfinite(noise))
    Fail("datagen: black noise {} codes: use a finite value >= 0", noise);
  Image out = display;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  float* v = out.data();
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double y = std::clamp(static_cast<double>(v[i]), 0.0, 1.0);
    const double n = noise > 0 ? noise * gauss(rng) : 0.0;  // drawn for every value: same stream
    // A clipped value stays clipped (the well is full whatever the dark noise).
    const double code = y >= 1 ? 255.0 : std::round(black + (255 - black) * y + n);
    v[i] = static_cast<float>(std::clamp(code, 0.0, 255.0) / 255.0);
  }
  return out;
}

}  // namespace hdr4d::datagen
