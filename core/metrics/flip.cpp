// FLIP (see flip.h for the definition). Images are held as float planes so that the separable
// filters run as vectorisable row and column passes; every output pixel depends on its inputs
// only, so the maps do not depend on the thread count.
#include "core/metrics/flip.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/metrics/magma_table.h"
#include "core/util/error.h"
#include "core/util/parallel.h"

namespace hdr4d {
namespace {

using Plane = std::vector<float>;
using Kernel = std::vector<float>;
constexpr double kPi = 3.14159265358979323846;

// ---- Colour spaces ----------------------------------------------------------------------------

// Linear sRGB (Rec. 709 primaries, D65 white) to CIE XYZ, as exact rationals.
constexpr double kRgbToXyz[3][3] = {
    {10135552.0 / 24577794.0, 8788810.0 / 24577794.0, 4435075.0 / 24577794.0},
    {2613072.0 / 12288897.0, 8788810.0 / 12288897.0, 887015.0 / 12288897.0},
    {1425312.0 / 73733382.0, 8788810.0 / 73733382.0, 70074185.0 / 73733382.0}};

struct ColourSpaces {
  float to_xyz[3][3];
  float to_rgb[3][3];  // the inverse, computed in double
  float white[3];      // XYZ of RGB (1,1,1): the D65 white point of the matrix
};

const ColourSpaces& Spaces() {
  static const ColourSpaces spaces = [] {
    ColourSpaces s{};
    const auto& m = kRgbToXyz;
    double inv[3][3];
    for (int r = 0; r < 3; ++r) {  // adjugate: cofactors of the transposed matrix
      for (int c = 0; c < 3; ++c) {
        const int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
        inv[r][c] = m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1];
      }
    }
    const double det = m[0][0] * inv[0][0] + m[0][1] * inv[1][0] + m[0][2] * inv[2][0];
    for (int r = 0; r < 3; ++r) {
      s.white[r] = static_cast<float>(m[r][0] + m[r][1] + m[r][2]);
      for (int c = 0; c < 3; ++c) {
        s.to_xyz[r][c] = static_cast<float>(m[r][c]);
        s.to_rgb[r][c] = static_cast<float>(inv[r][c] / det);
      }
    }
    return s;
  }();
  return spaces;
}

std::array<float, 3> Multiply(const float (&m)[3][3], float a, float b, float c) {
  return {m[0][0] * a + m[0][1] * b + m[0][2] * c, m[1][0] * a + m[1][1] * b + m[1][2] * c,
          m[2][0] * a + m[2][1] * b + m[2][2] * c};
}

// YCxCz: CIELab without its cube root, i.e. linear in XYZ, so it can be filtered.
std::array<float, 3> LinearRgbToYcxcz(float r, float g, float b) {
  const ColourSpaces& s = Spaces();
  const auto xyz = Multiply(s.to_xyz, r, g, b);
  const float x = xyz[0] / s.white[0], y = xyz[1] / s.white[1], z = xyz[2] / s.white[2];
  return {116.0f * y - 16.0f, 500.0f * (x - y), 200.0f * (y - z)};
}

std::array<float, 3> YcxczToLinearRgb(float yy, float cx, float cz) {
  const ColourSpaces& s = Spaces();
  const float y = (yy + 16.0f) / 116.0f;
  const float x = y + cx / 500.0f, z = y - cz / 200.0f;
  return Multiply(s.to_rgb, x * s.white[0], y * s.white[1], z * s.white[2]);
}

// Cube root of t > 0 by three Newton steps from a bit-level guess (within a few float ulps;
// std::cbrt was a sixth of FLIP's time).
float CubeRoot(float t) {
  std::uint32_t bits;
  std::memcpy(&bits, &t, sizeof bits);
  bits = bits / 3 + 709921077u;  // divides the exponent by 3, close enough to start
  float y;
  std::memcpy(&y, &bits, sizeof y);
  for (int i = 0; i < 3; ++i) y = (2.0f * y + t / (y * y)) * (1.0f / 3.0f);
  return y;
}

float LabF(float t) {
  constexpr float kDelta = 6.0f / 29.0f;
  if (t > kDelta * kDelta * kDelta) return CubeRoot(t);
  return t / (3.0f * kDelta * kDelta) + 4.0f / 29.0f;
}

// CIELab of linear RGB with the Hunt adjustment: chroma falls with lightness (a, b times
// 0.01 L), as the eye sees less colour difference in dark colours.
std::array<float, 3> HuntLab(float r, float g, float b) {
  const ColourSpaces& s = Spaces();
  const auto xyz = Multiply(s.to_xyz, r, g, b);
  const float fx = LabF(xyz[0] / s.white[0]), fy = LabF(xyz[1] / s.white[1]),
              fz = LabF(xyz[2] / s.white[2]);
  const float l = 116.0f * fy - 16.0f;
  return {l, 0.01f * l * 500.0f * (fx - fy), 0.01f * l * 200.0f * (fy - fz)};
}

// HyAB: city-block in lightness, Euclidean in the chroma plane (better for large differences).
float HyAb(const std::array<float, 3>& p, const std::array<float, 3>& q) {
  const float da = p[1] - q[1], db = p[2] - q[2];
  return std::fabs(p[0] - q[0]) + std::sqrt(da * da + db * db);
}

constexpr float kColourExponent = 0.7f;    // q_c
constexpr float kColourCutoff = 0.4f;      // p_c: the share of the maximum mapped to p_t
constexpr float kColourCompressed = 0.95f;  // p_t
// q_f, the feature exponent, is 0.5: a square root (LdrFlipLinear).
constexpr float kFeatureWidth = 0.082f;    // w: degrees, twice the detector's sigma

// The largest colour difference: pure green against pure blue, after the same pipeline.
float MaxColourDifference() {
  return std::pow(HyAb(HuntLab(0, 1, 0), HuntLab(0, 0, 1)), kColourExponent);
}

// ---- Filters ----------------------------------------------------------------------------------

// The contrast sensitivity filters of the colour pipeline, 1-D factors of 2-D filters: Y and Cx
// each a Gaussian a sqrt(pi/b) exp(-pi^2 x^2 / b) of x in degrees (a = 1; b = 0.0047, 0.0053),
// Cz the sum of two (a = 34.1, b = 0.04 and a = 13.5, b = 0.025), each 2-D term separated into
// the square of its root, both scaled so that the 2-D sum is 1.
struct SpatialKernels {
  Kernel y, cx, cz1, cz2;
};

SpatialKernels MakeSpatialKernels(double ppd) {
  const double widest_b = 0.04;
  const int radius = static_cast<int>(std::ceil(3.0 * std::sqrt(widest_b / (2 * kPi * kPi)) * ppd));
  auto gaussian = [&](double x, double a, double b) {
    return a * std::sqrt(kPi / b) * std::exp(-kPi * kPi * x * x / b);
  };
  std::vector<double> y, cx, cz1, cz2;
  double sy = 0, scx = 0, s1 = 0, s2 = 0;
  for (int i = -radius; i <= radius; ++i) {
    const double x = i / ppd;
    y.push_back(gaussian(x, 1.0, 0.0047));
    cx.push_back(gaussian(x, 1.0, 0.0053));
    cz1.push_back(std::sqrt(gaussian(0, 34.1, 0.04)) * std::exp(-kPi * kPi * x * x / 0.04));
    cz2.push_back(std::sqrt(gaussian(0, 13.5, 0.025)) * std::exp(-kPi * kPi * x * x / 0.025));
    sy += y.back(), scx += cx.back(), s1 += cz1.back(), s2 += cz2.back();
  }
  const double scz = std::sqrt(s1 * s1 + s2 * s2);
  SpatialKernels k;
  for (std::size_t i = 0; i < y.size(); ++i) {
    k.y.push_back(static_cast<float>(y[i] / sy));
    k.cx.push_back(static_cast<float>(cx[i] / scx));
    k.cz1.push_back(static_cast<float>(cz1[i] / scz));
    k.cz2.push_back(static_cast<float>(cz2[i] / scz));
  }
  return k;
}

// The feature detector: a Gaussian of sigma w/2 degrees (in pixels: 0.5 w ppd), its first and
// second derivatives; the Gaussian sums to 1, each derivative's positive weights to 1 and its
// negative weights to -1.
struct FeatureKernels {
  Kernel g, dg, ddg;
};

FeatureKernels MakeFeatureKernels(double ppd) {
  const double sigma = 0.5 * kFeatureWidth * ppd;
  const int radius = static_cast<int>(std::ceil(3.0 * sigma));
  std::vector<double> g, dg, ddg;
  for (int i = -radius; i <= radius; ++i) {
    const double v = std::exp(-double(i) * i / (2 * sigma * sigma));
    g.push_back(v);
    dg.push_back(-i * v);
    ddg.push_back((double(i) * i / (sigma * sigma) - 1.0) * v);
  }
  auto normalised = [](const std::vector<double>& w, bool split_signs) {
    double pos = 0, neg = 0;
    for (double v : w) (v > 0 ? pos : neg) += std::fabs(v);
    Kernel out;
    for (double v : w) {
      const double scale = !split_signs ? pos + neg : (v > 0 ? pos : neg);
      out.push_back(scale > 0 ? static_cast<float>(v / scale) : 0.0f);
    }
    return out;
  };
  return {normalised(g, false), normalised(dg, true), normalised(ddg, true)};
}

// Calls fn(i) for every pixel index i in [0, n), in parallel chunks.
template <typename Fn>
void ForEachPixel(std::size_t n, Fn&& fn) {
  ParallelFor(static_cast<std::int64_t>(n), 16384, [&fn](std::int64_t i) { fn(std::size_t(i)); });
}

std::int64_t RowGrain(int width) {
  return std::max<std::int64_t>(1, 16384 / std::max(1, width));
}

// dst = src filtered along each row with kernel k (odd length); pixels beyond the border repeat
// the edge pixel.
Plane FilterRows(const Plane& src, int w, int h, const Kernel& k) {
  const int r = static_cast<int>(k.size()) / 2;
  Plane dst(src.size(), 0.0f);
  ParallelForChunks(h, RowGrain(w), [&](std::int64_t begin, std::int64_t end) {
    std::vector<float> padded(static_cast<std::size_t>(w) + 2 * r);
    for (std::int64_t y = begin; y < end; ++y) {
      const float* row = src.data() + y * w;
      for (int i = 0; i < w + 2 * r; ++i) padded[i] = row[std::clamp(i - r, 0, w - 1)];
      float* out = dst.data() + y * w;
      for (std::size_t t = 0; t < k.size(); ++t) {
        const float weight = k[t];
        const float* in = padded.data() + t;
        for (int x = 0; x < w; ++x) out[x] += weight * in[x];
      }
    }
  });
  return dst;
}

// dst = src filtered along each column with kernel k, edge pixels repeated.
Plane FilterColumns(const Plane& src, int w, int h, const Kernel& k) {
  const int r = static_cast<int>(k.size()) / 2;
  Plane dst(src.size(), 0.0f);
  ParallelForChunks(h, RowGrain(w), [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t y = begin; y < end; ++y) {
      float* out = dst.data() + y * w;
      for (std::size_t t = 0; t < k.size(); ++t) {
        const std::int64_t yy = std::clamp<std::int64_t>(y + std::int64_t(t) - r, 0, h - 1);
        const float weight = k[t];
        const float* in = src.data() + yy * w;
        for (int x = 0; x < w; ++x) out[x] += weight * in[x];
      }
    }
  });
  return dst;
}

Plane Filter2d(const Plane& src, int w, int h, const Kernel& along_x, const Kernel& along_y) {
  return FilterColumns(FilterRows(src, w, h, along_x), w, h, along_y);
}

// ---- LDR-FLIP on linear RGB -------------------------------------------------------------------

// Linear RGB, interleaved, 3 values per pixel, in [0,1].
struct LinearRgb {
  int w = 0, h = 0;
  std::vector<float> rgb;
};

struct Opponent {
  Plane y, cx, cz;
};

Opponent ToOpponent(const LinearRgb& image) {
  const std::size_t n = static_cast<std::size_t>(image.w) * image.h;
  Opponent o{Plane(n), Plane(n), Plane(n)};
  ForEachPixel(n, [&](std::size_t i) {
    const float* p = image.rgb.data() + 3 * i;
    const auto v = LinearRgbToYcxcz(p[0], p[1], p[2]);
    o.y[i] = v[0], o.cx[i] = v[1], o.cz[i] = v[2];
  });
  return o;
}

// The opponent planes as the eye resolves them at `ppd`.
Opponent Blurred(const Opponent& o, int w, int h, const SpatialKernels& k) {
  Opponent b{Filter2d(o.y, w, h, k.y, k.y), Filter2d(o.cx, w, h, k.cx, k.cx),
             Filter2d(o.cz, w, h, k.cz1, k.cz1)};
  const Plane second = Filter2d(o.cz, w, h, k.cz2, k.cz2);
  for (std::size_t i = 0; i < b.cz.size(); ++i) b.cz[i] += second[i];
  return b;
}

// The colour difference per pixel, in [0,1].
Plane ColourDifference(const Opponent& ref, const Opponent& test, int w, int h, double ppd) {
  const SpatialKernels kernels = MakeSpatialKernels(ppd);
  const Opponent a = Blurred(ref, w, h, kernels), b = Blurred(test, w, h, kernels);
  const float cmax = MaxColourDifference(), cutoff = kColourCutoff * cmax;
  auto lab = [](const Opponent& o, std::size_t i) {
    auto rgb = YcxczToLinearRgb(o.y[i], o.cx[i], o.cz[i]);
    for (float& c : rgb) c = std::clamp(c, 0.0f, 1.0f);
    return HuntLab(rgb[0], rgb[1], rgb[2]);
  };
  Plane diff(a.y.size());
  ParallelForChunks(h, RowGrain(w), [&](std::int64_t begin, std::int64_t end) {
    for (std::size_t i = begin * w; i < static_cast<std::size_t>(end) * w; ++i) {
      const float d = std::pow(HyAb(lab(a, i), lab(b, i)), kColourExponent);
      // [0, cutoff] -> [0, 0.95] and [cutoff, cmax] -> [0.95, 1]: small differences spread out.
      diff[i] = d < cutoff ? d * kColourCompressed / cutoff
                           : kColourCompressed + (d - cutoff) / (cmax - cutoff) *
                                                     (1.0f - kColourCompressed);
    }
  });
  return diff;
}

// Edge and point strength of the normalised luminance (Y + 16) / 116 of an opponent image.
struct Features {
  Plane edge, point;
};

Features DetectFeatures(const Plane& y_opponent, int w, int h, const FeatureKernels& k) {
  Plane lum(y_opponent.size());
  for (std::size_t i = 0; i < lum.size(); ++i) lum[i] = (y_opponent[i] + 16.0f) / 116.0f;
  const Plane gx = FilterRows(lum, w, h, k.g), dgx = FilterRows(lum, w, h, k.dg),
              ddgx = FilterRows(lum, w, h, k.ddg);
  const Plane dx = FilterColumns(dgx, w, h, k.g), dy = FilterColumns(gx, w, h, k.dg);
  const Plane ddx = FilterColumns(ddgx, w, h, k.g), ddy = FilterColumns(gx, w, h, k.ddg);
  Features f{Plane(lum.size()), Plane(lum.size())};
  ForEachPixel(lum.size(), [&](std::size_t i) {
    f.edge[i] = std::sqrt(dx[i] * dx[i] + dy[i] * dy[i]);
    f.point[i] = std::sqrt(ddx[i] * ddx[i] + ddy[i] * ddy[i]);
  });
  return f;
}

// LDR-FLIP of two linear-RGB images in [0,1].
Plane LdrFlipLinear(const LinearRgb& ref, const LinearRgb& test, double ppd) {
  const int w = ref.w, h = ref.h;
  const Opponent ref_o = ToOpponent(ref), test_o = ToOpponent(test);
  Plane flip = ColourDifference(ref_o, test_o, w, h, ppd);
  const FeatureKernels kernels = MakeFeatureKernels(ppd);
  const Features a = DetectFeatures(ref_o.y, w, h, kernels);
  const Features b = DetectFeatures(test_o.y, w, h, kernels);
  const float inv_sqrt2 = 1.0f / std::sqrt(2.0f);
  ForEachPixel(flip.size(), [&](std::size_t i) {
    const float feature = std::max(std::fabs(a.edge[i] - b.edge[i]),
                                   std::fabs(a.point[i] - b.point[i]));
    const float feature_difference = std::sqrt(inv_sqrt2 * feature);
    // Features sharpen the colour error: the exponent falls from 1 towards 0 where they differ.
    flip[i] = std::pow(flip[i], 1.0f - feature_difference);
  });
  return flip;
}

// ---- Inputs -----------------------------------------------------------------------------------

void CheckFlipPair(const Image& pred, const Image& gt) {
  if (!pred.SameShape(gt)) {
    Fail("FLIP: prediction and ground truth images differ in shape: {} vs {}", pred.ShapeString(),
         gt.ShapeString());
  }
  if (pred.empty()) Fail("FLIP: prediction and ground truth images are empty");
  for (const Image* image : {&pred, &gt}) {
    const long bad = FirstNonFinite(*image);
    if (bad >= 0) {
      Fail("FLIP: {} image has a non-finite value at value index {}",
           image == &pred ? "prediction" : "ground truth", bad);
    }
  }
}

// The first three channels as linear values (a 1- or 2-channel image is grey), decoded from
// sRGB when the image is display-encoded; clamped to [0,1] when `clamp` is set.
// SrgbToLinear, from a table where the value is exactly an 8-bit code k / 255 (PNG truth).
float DecodeSrgb(float v) {
  static const auto table = [] {
    std::array<std::array<float, 2>, 256> t{};
    for (int k = 0; k < 256; ++k) t[k] = {float(k) / 255.0f, SrgbToLinear(float(k) / 255.0f)};
    return t;
  }();
  const float scaled = v * 255.0f;
  if (scaled >= 0.0f && scaled <= 255.0f) {
    const auto& entry = table[static_cast<int>(scaled + 0.5f)];
    if (entry[0] == v) return entry[1];
  }
  return SrgbToLinear(v);
}

LinearRgb ToLinearRgb(const Image& image, bool clamp) {
  LinearRgb out{image.width(), image.height(), std::vector<float>(image.num_pixels() * 3)};
  const int channels = image.channels();
  const bool srgb = image.encoding() == Encoding::kSrgb;
  ForEachPixel(image.num_pixels(), [&](std::size_t i) {
    for (int c = 0; c < 3; ++c) {
      float v = image.data()[i * channels + (channels >= 3 ? c : 0)];
      if (srgb) v = DecodeSrgb(v);
      out.rgb[3 * i + c] = clamp ? std::clamp(v, 0.0f, 1.0f) : v;
    }
  });
  return out;
}

Image MapImage(const Plane& plane, int w, int h) {
  Image map(w, h, 1, Encoding::kLinear);
  std::copy(plane.begin(), plane.end(), map.data());
  return map;
}

// ---- HDR-FLIP ---------------------------------------------------------------------------------

// The reference's ACES fit (Narkowicz) with its 0.6 pre-exposure folded in:
// (c0 x^2 + c1 x) / (c3 x^2 + c4 x + c5).
constexpr float kAces[6] = {0.6f * 0.6f * 2.51f, 0.6f * 0.03f, 0.0f,
                            0.6f * 0.6f * 2.43f, 0.6f * 0.59f, 0.14f};

float Aces(float x) {
  // Its denominator has no real root; far out it tends to c0 / c3 > 1, which the clamp makes 1
  // (and x^2 would overflow).
  if (!(std::fabs(x) < 1e6f)) return 1.0f;
  const float v = (kAces[0] * x * x + kAces[1] * x + kAces[2]) /
                  (kAces[3] * x * x + kAces[4] * x + kAces[5]);
  return std::clamp(v, 0.0f, 1.0f);
}

// The linear value that ACES maps to `target`: the larger root of
// (c0 - t c3) x^2 + (c1 - t c4) x + (c2 - t c5) = 0.
double AcesInverse(double t) {
  const double a = kAces[0] - t * kAces[3], b = kAces[1] - t * kAces[4];
  const double c = kAces[2] - t * kAces[5];
  if (a == 0.0) return -c / b;
  const double mid = -0.5 * b / a;
  return mid + std::sqrt(std::max(0.0, mid * mid - c / a));
}

float ReferenceLuminance(const float* rgb) {
  return 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2];
}

LinearRgb ExposedAndToneMapped(const LinearRgb& image, float scale) {
  LinearRgb out{image.w, image.h, std::vector<float>(image.rgb.size())};
  ForEachPixel(out.rgb.size(), [&](std::size_t i) { out.rgb[i] = Aces(image.rgb[i] * scale); });
  return out;
}

}  // namespace

// ---- Public -------------------------------------------------------------------------------------

Image FlipMap(const Image& pred, const Image& gt, double ppd) {
  CheckFlipPair(pred, gt);
  if (!(ppd > 0.0) || !std::isfinite(ppd)) Fail("FLIP: pixels per degree must be > 0, got {}", ppd);
  return MapImage(LdrFlipLinear(ToLinearRgb(gt, true), ToLinearRgb(pred, true), ppd), gt.width(),
                  gt.height());
}

double Flip(const Image& pred, const Image& gt, double ppd) {
  return FlipMean(FlipMap(pred, gt, ppd));
}

HdrFlipExposures HdrFlipExposureRange(const Image& gt) {
  if (gt.empty()) Fail("HDR-FLIP: the ground truth image is empty");
  const LinearRgb rgb = ToLinearRgb(gt, false);
  std::vector<float> lum(gt.num_pixels());
  for (std::size_t i = 0; i < lum.size(); ++i) lum[i] = ReferenceLuminance(&rgb.rgb[3 * i]);
  const float max_lum = *std::max_element(lum.begin(), lum.end());
  if (!(max_lum > 0.0f)) {
    Fail("HDR-FLIP: the ground truth has no pixel with positive luminance (max {}), so it has no "
         "exposure range",
         max_lum);
  }
  auto median = [](std::vector<float> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  float median_lum = median(lum);
  if (!(median_lum > 0.0f)) {
    std::vector<float> positive;
    for (float v : lum) {
      if (v > 0.0f) positive.push_back(v);
    }
    median_lum = median(positive);
  }
  const double x85 = AcesInverse(0.85);
  HdrFlipExposures range;
  range.start = std::log2(x85 / max_lum);
  range.stop = std::log2(x85 / median_lum);
  range.count = static_cast<int>(std::max(2.0, std::ceil(range.stop - range.start)));
  return range;
}

Image HdrFlipMap(const Image& pred, const Image& gt, double ppd) {
  CheckFlipPair(pred, gt);
  if (!(ppd > 0.0) || !std::isfinite(ppd)) Fail("FLIP: pixels per degree must be > 0, got {}", ppd);
  const HdrFlipExposures range = HdrFlipExposureRange(gt);
  const LinearRgb ref = ToLinearRgb(gt, false), test = ToLinearRgb(pred, false);
  const double step = (range.stop - range.start) / (range.count - 1);
  Plane worst(gt.num_pixels(), 0.0f);
  for (int i = 0; i < range.count; ++i) {
    const float scale = std::exp2(static_cast<float>(range.start + i * step));
    const Plane flip = LdrFlipLinear(ExposedAndToneMapped(ref, scale),
                                     ExposedAndToneMapped(test, scale), ppd);
    for (std::size_t p = 0; p < worst.size(); ++p) worst[p] = std::max(worst[p], flip[p]);
  }
  return MapImage(worst, gt.width(), gt.height());
}

double HdrFlip(const Image& pred, const Image& gt, double ppd) {
  return FlipMean(HdrFlipMap(pred, gt, ppd));
}

double FlipMean(const Image& map) {
  if (map.empty() || map.channels() != 1) {
    Fail("FLIP: a mean needs a non-empty one-channel map, got {}", map.ShapeString());
  }
  double sum = 0.0;
  for (float v : map.values()) sum += v;
  return sum / static_cast<double>(map.size());
}

Image FlipMagma(const Image& map) {
  if (map.channels() != 1) Fail("FLIP: magma colours a one-channel map, got {}", map.ShapeString());
  const auto& table = MagmaTable();
  Image out(map.width(), map.height(), 3, Encoding::kSrgb);
  for (std::size_t i = 0; i < map.num_pixels(); ++i) {
    const float v = std::clamp(map.values()[i], 0.0f, 1.0f);
    const auto& colour = table[static_cast<std::size_t>(v * 255.0f + 0.5f)];
    for (int c = 0; c < 3; ++c) out.data()[3 * i + c] = colour[c];
  }
  return out;
}

}  // namespace hdr4d
