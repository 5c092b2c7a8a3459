#include "core/metrics/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/util/error.h"
#include "core/util/parallel.h"

namespace hdr4d {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// An interleaved double image: the intermediate form of the HDR metrics, so that
// normalised / encoded values are not rounded to float before they are compared.
struct Values {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<double> v;
};

// Rows per ParallelFor chunk so that one chunk holds roughly `values` numbers.
std::int64_t RowGrain(int width, int channels, std::int64_t values = 16384) {
  return std::max<std::int64_t>(1,
                                values / std::max<std::int64_t>(1, std::int64_t{width} * channels));
}

void CheckFinite(const Image& image, const char* role) {
  const long bad = FirstNonFinite(image);
  if (bad < 0) return;
  const long pixel = bad / image.channels();
  Fail("{} image has a non-finite value ({}) at x={}, y={}, channel {}", role, image.values()[bad],
       pixel % image.width(), pixel / image.width(), bad % image.channels());
}

// The common input contract of every metric: same shape, not empty, finite.
void CheckPair(const Image& a, const Image& b, const char* role_a, const char* role_b) {
  if (!a.SameShape(b)) {
    Fail("{} and {} images differ in shape: {} vs {}", role_a, role_b, a.ShapeString(),
         b.ShapeString());
  }
  if (a.empty()) Fail("{} and {} images are empty ({})", role_a, role_b, a.ShapeString());
  CheckFinite(a, role_a);
  CheckFinite(b, role_b);
}

double PsnrFromMse(double mse, double peak) {
  return mse == 0.0 ? kInf : 10.0 * std::log10(peak * peak / mse);
}

// Sum of squared differences per channel, reduced over rows in row order (deterministic).
template <typename T>
std::vector<double> SquaredErrorPerChannel(
    const T* a, const T* b, int width, int height, int channels) {
  const std::size_t row_len = static_cast<std::size_t>(width) * channels;
  std::vector<double> rows(static_cast<std::size_t>(height) * channels, 0.0);
  ParallelFor(height, RowGrain(width, channels), [&](std::int64_t y) {
    double* sums = &rows[y * channels];
    const T* pa = a + y * row_len;
    const T* pb = b + y * row_len;
    for (std::size_t i = 0; i < row_len; ++i) {
      const double d = static_cast<double>(pa[i]) - static_cast<double>(pb[i]);
      sums[i % channels] += d * d;
    }
  });
  std::vector<double> total(channels, 0.0);
  for (int y = 0; y < height; ++y) {
    for (int c = 0; c < channels; ++c) total[c] += rows[static_cast<std::size_t>(y) * channels + c];
  }
  return total;
}

template <typename T>
double Mse(const T* a, const T* b, int width, int height, int channels) {
  const std::vector<double> per_channel = SquaredErrorPerChannel(a, b, width, height, channels);
  double sum = 0.0;
  for (double s : per_channel) sum += s;
  return sum / (static_cast<double>(width) * height * channels);
}

constexpr int kSsimRadius = kSsimWindow / 2;
constexpr int kSsimQuantities = 5;  // a, b, a^2, b^2, ab

// The rows r0..r1 of a band of SSIM's separable window sum, row_len values each.
struct SsimBand {
  std::int64_t r0, r1;
  std::size_t rows, row_len;
  int channels;
};

// The horizontal pass over a band: the five per-pixel products of every row, zero-padded by the
// window radius, filtered along the row into horizontal[q][(r - r0) * row_len + i].
template <typename T>
void SsimHorizontalPass(const T* a,
                        const T* b,
                        const SsimBand& band,
                        const std::array<double, kSsimWindow>& g,
                        std::vector<double>* horizontal) {
  const std::size_t row_len = band.row_len;
  const std::size_t pad = static_cast<std::size_t>(kSsimRadius) * band.channels;
  const std::size_t padded_len = row_len + 2 * pad;
  // One zero-padded row of each product; the pads stay zero.
  std::vector<double> padded(kSsimQuantities * padded_len, 0.0);
  for (std::int64_t r = band.r0; r < band.r1; ++r) {
    const T* pa = a + r * row_len;
    const T* pb = b + r * row_len;
    double* qa = &padded[0 * padded_len + pad];
    double* qb = &padded[1 * padded_len + pad];
    double* qaa = &padded[2 * padded_len + pad];
    double* qbb = &padded[3 * padded_len + pad];
    double* qab = &padded[4 * padded_len + pad];
    for (std::size_t i = 0; i < row_len; ++i) {
      const double x = static_cast<double>(pa[i]);
      const double y = static_cast<double>(pb[i]);
      qa[i] = x;
      qb[i] = y;
      qaa[i] = x * x;
      qbb[i] = y * y;
      qab[i] = x * y;
    }
    for (int q = 0; q < kSsimQuantities; ++q) {
      const double* src = &padded[q * padded_len];
      double* dst = &(*horizontal)[(q * band.rows + (r - band.r0)) * row_len];
      for (std::size_t i = 0; i < row_len; ++i) dst[i] = g[0] * src[i];
      for (int k = 1; k < kSsimWindow; ++k) {
        const double w = g[k];
        const double* s = src + static_cast<std::size_t>(k) * band.channels;
        for (std::size_t i = 0; i < row_len; ++i) dst[i] += w * s[i];
      }
    }
  }
}

// Output row y: the vertical pass over the band's filtered rows (skipping the zero rows outside
// the image) into `filtered`, then SSIM per value, written to `out` when non-null; returns the
// row's sum in value order.
double SsimRow(std::int64_t y,
               const SsimBand& band,
               const std::vector<double>& horizontal,
               const std::array<double, kSsimWindow>& g,
               double c1,
               double c2,
               std::vector<double>* filtered,
               float* out) {
  const std::size_t row_len = band.row_len;
  for (int q = 0; q < kSsimQuantities; ++q) {
    double* dst = &(*filtered)[q * row_len];
    std::fill(dst, dst + row_len, 0.0);
    for (int k = 0; k < kSsimWindow; ++k) {
      const std::int64_t r = y + k - kSsimRadius;
      if (r < band.r0 || r >= band.r1) continue;  // outside the image: a zero row
      const double w = g[k];
      const double* src = &horizontal[(q * band.rows + (r - band.r0)) * row_len];
      for (std::size_t i = 0; i < row_len; ++i) dst[i] += w * src[i];
    }
  }
  const double* mu_a = &(*filtered)[0 * row_len];
  const double* mu_b = &(*filtered)[1 * row_len];
  const double* e_aa = &(*filtered)[2 * row_len];
  const double* e_bb = &(*filtered)[3 * row_len];
  const double* e_ab = &(*filtered)[4 * row_len];
  double sum = 0.0;
  for (std::size_t i = 0; i < row_len; ++i) {
    const double mu_aa = mu_a[i] * mu_a[i];
    const double mu_bb = mu_b[i] * mu_b[i];
    const double mu_ab = mu_a[i] * mu_b[i];
    const double var_a = e_aa[i] - mu_aa;
    const double var_b = e_bb[i] - mu_bb;
    const double cov = e_ab[i] - mu_ab;
    const double s =
        ((2.0 * mu_ab + c1) * (2.0 * cov + c2)) / ((mu_aa + mu_bb + c1) * (var_a + var_b + c2));
    if (out) out[i] = static_cast<float>(s);
    sum += s;
  }
  return sum;
}

// Windowed SSIM on interleaved images. Zero padding makes the 2-D window sum separable exactly:
// a horizontal pass over the five per-pixel products (a, b, a^2, b^2, ab) of every needed row,
// then a vertical pass, both skipping the zeros outside the image. Rows are processed in
// bands (each band redoes the horizontal pass of the 2*5 rows it shares with its neighbours)
// so memory stays O(band * width) and bands run in parallel. Writes the map when `map` is
// non-null; returns the sum of the map over all pixels and channels, reduced in row order.
template <typename T>
double SsimCore(
    const T* a, const T* b, int width, int height, int channels, double c1, double c2, float* map) {
  static const std::array<double, kSsimWindow> g = SsimGaussianKernel();
  const std::size_t row_len = static_cast<std::size_t>(width) * channels;
  constexpr std::int64_t kBand = 32;
  std::vector<double> row_sums(height, 0.0);
  ParallelForChunks(height, kBand, [&](std::int64_t y0, std::int64_t y1) {
    SsimBand band;
    band.r0 = std::max<std::int64_t>(0, y0 - kSsimRadius);
    band.r1 = std::min<std::int64_t>(height, y1 + kSsimRadius);
    band.rows = static_cast<std::size_t>(band.r1 - band.r0);
    band.row_len = row_len;
    band.channels = channels;
    std::vector<double> horizontal(kSsimQuantities * band.rows * row_len);
    SsimHorizontalPass(a, b, band, g, &horizontal);
    std::vector<double> filtered(kSsimQuantities * row_len);
    for (std::int64_t y = y0; y < y1; ++y)
      row_sums[y] =
          SsimRow(y, band, horizontal, g, c1, c2, &filtered, map ? map + y * row_len : nullptr);
  });
  double total = 0.0;
  for (double s : row_sums) total += s;
  return total;
}

void CheckSsimConstants(double c1, double c2) {
  if (!(c1 > 0.0) || !(c2 > 0.0) || !std::isfinite(c1) || !std::isfinite(c2)) {
    Fail("SSIM constants must be positive and finite (c1 = {}, c2 = {})", c1, c2);
  }
}

double SsimOf(const Values& a, const Values& b, double c1, double c2) {
  HDR4D_CHECK(a.width == b.width && a.height == b.height && a.channels == b.channels);
  const double sum =
      SsimCore(a.v.data(), b.v.data(), a.width, a.height, a.channels, c1, c2, nullptr);
  return sum / (static_cast<double>(a.width) * a.height * a.channels);
}

double PsnrOf(const Values& a, const Values& b, double peak) {
  HDR4D_CHECK(a.width == b.width && a.height == b.height && a.channels == b.channels);
  return PsnrFromMse(Mse(a.v.data(), b.v.data(), a.width, a.height, a.channels), peak);
}

// fn(value) for every value of `image` (same shape, as doubles), rows in parallel.
template <typename Fn>
Values MapValues(const Image& image, Fn fn) {
  Values out{image.width(), image.height(), image.channels(), std::vector<double>(image.size())};
  const std::size_t row_len = static_cast<std::size_t>(image.width()) * image.channels();
  const float* src = image.data();
  ParallelFor(image.height(), RowGrain(image.width(), image.channels()), [&](std::int64_t y) {
    for (std::size_t i = y * row_len; i < (y + 1) * row_len; ++i) out.v[i] = fn(src[i]);
  });
  return out;
}

// The RGB channels of an HDR pair, checked (same shape, non-empty, finite).
std::pair<Image, Image> RgbPair(const Image& pred, const Image& gt) {
  // Check the full images first so a non-finite alpha is reported too and shapes read as given.
  CheckPair(pred, gt, "prediction", "ground truth");
  return {pred.Rgb(), gt.Rgb()};
}

double MaxForNormalising(const Image& image, const char* role) {
  const double m = image.MaxValue();
  if (!(m > 0.0) || !std::isfinite(m)) {
    Fail(
        "{} HDR image has maximum {} (all black or negative): it cannot be normalised by its "
        "maximum",
        role, m);
  }
  return m;
}

// A prediction's own maximum, to normalise it by. One that is all black (or nowhere positive)
// has none: it is scored as black, every mu-law value 0, a low score rather than an error that
// took a run's final evaluation with it (a model that lost its Gaussians, stop 94 sweep).
double PredictionMax(const Image& pred_rgb) {
  const double m = pred_rgb.MaxValue();
  return m <= 0.0 ? 1.0 : MaxForNormalising(pred_rgb, "prediction");
}

// The mu-law images that MuPsnr / MuSsim compare.
std::pair<Values, Values> MuLawPair(const Image& pred_rgb,
                                    const Image& gt_rgb,
                                    HdrNormalisation normalisation) {
  const double gt_max = MaxForNormalising(gt_rgb, "ground-truth");
  const double pred_max =
      normalisation == HdrNormalisation::kOwnMax ? PredictionMax(pred_rgb) : gt_max;
  const double inv_log = 1.0 / std::log1p(kMuLawMu);
  auto encode = [inv_log](double x, double max) {
    return std::log1p(kMuLawMu * std::clamp(x / max, 0.0, 1.0)) * inv_log;
  };
  return {MapValues(pred_rgb, [&](float x) { return encode(x, pred_max); }),
          MapValues(gt_rgb, [&](float x) { return encode(x, gt_max); })};
}

// PU21 `banding_glare` coefficients (Mantiuk and Azimi 2021, the pu21 reference code).
constexpr double kP1 = 0.353487901;
constexpr double kP2 = 0.3734658629;
constexpr double kP3 = 8.277049286e-05;
constexpr double kP4 = 0.9062562627;
constexpr double kP5 = 0.09150303166;
constexpr double kP6 = 0.9099517204;
constexpr double kP7 = 596.3148142;

// Luminance (or the single grey value) per pixel, times `scale`.
Values ScaledLuminance(const Image& rgb, double scale) {
  Values out{rgb.width(), rgb.height(), 1, std::vector<double>(rgb.num_pixels())};
  const int channels = rgb.channels();
  const float* src = rgb.data();
  ParallelFor(rgb.height(), RowGrain(rgb.width(), channels), [&](std::int64_t y) {
    for (std::size_t p = y * rgb.width(); p < (y + 1) * static_cast<std::size_t>(rgb.width());
         ++p) {
      const float* px = src + p * channels;
      out.v[p] = scale * (channels == 1 ? px[0] : Luminance(px[0], px[1], px[2]));
    }
  });
  return out;
}

void CheckPu21Channels(const Image& rgb) {
  if (rgb.channels() != 1 && rgb.channels() != 3) {
    Fail("PU21 needs a 1-channel (luminance) or an RGB image, got {} channels", rgb.channels());
  }
}

double Pu21ScaleOfRgb(const Image& gt_rgb) {
  CheckPu21Channels(gt_rgb);
  const Values lum = ScaledLuminance(gt_rgb, 1.0);
  const double max_lum = *std::max_element(lum.v.begin(), lum.v.end());
  if (!(max_lum > 0.0) || !std::isfinite(max_lum)) {
    Fail(
        "ground-truth HDR image has maximum luminance {} (all black): PU21 cannot scale it to "
        "absolute units",
        max_lum);
  }
  return kPu21DisplayPeak / max_lum;
}

}  // namespace

std::array<double, kSsimWindow> SsimGaussianKernel() {
  std::array<double, kSsimWindow> g{};
  double sum = 0.0;
  for (int k = 0; k < kSsimWindow; ++k) {
    const double d = k - kSsimWindow / 2;
    g[k] = std::exp(-d * d / (2.0 * kSsimSigma * kSsimSigma));
    sum += g[k];
  }
  for (double& v : g) v /= sum;
  return g;
}

// ---- PSNR ------------------------------------------------------------------------------------

double MeanSquaredError(const Image& pred, const Image& gt) {
  CheckPair(pred, gt, "prediction", "ground truth");
  return Mse(pred.data(), gt.data(), pred.width(), pred.height(), pred.channels());
}

double Psnr(const Image& pred, const Image& gt) {
  return PsnrFromMse(MeanSquaredError(pred, gt), 1.0);
}

double PsnrChannelMean(const Image& pred, const Image& gt) {
  CheckPair(pred, gt, "prediction", "ground truth");
  const std::vector<double> sums =
      SquaredErrorPerChannel(pred.data(), gt.data(), pred.width(), pred.height(), pred.channels());
  double total = 0.0;
  for (double s : sums) total += PsnrFromMse(s / static_cast<double>(pred.num_pixels()), 1.0);
  return total / pred.channels();
}

// ---- SSIM ------------------------------------------------------------------------------------

double Ssim(const Image& a, const Image& b, double c1, double c2) {
  CheckPair(a, b, "first (prediction)", "second (ground truth)");
  CheckSsimConstants(c1, c2);
  const double sum =
      SsimCore(a.data(), b.data(), a.width(), a.height(), a.channels(), c1, c2, nullptr);
  return sum / static_cast<double>(a.size());
}

Image SsimMap(const Image& a, const Image& b, double c1, double c2) {
  CheckPair(a, b, "first (prediction)", "second (ground truth)");
  CheckSsimConstants(c1, c2);
  Image map(a.width(), a.height(), a.channels(), Encoding::kLinear);
  SsimCore(a.data(), b.data(), a.width(), a.height(), a.channels(), c1, c2, map.data());
  return map;
}

// ---- mu-law ----------------------------------------------------------------------------------

Image MuLaw(const Image& x, double mu) {
  if (!(mu > 0.0) || !std::isfinite(mu)) Fail("mu-law: mu must be positive and finite, got {}", mu);
  Image out = x;
  const double inv_log = 1.0 / std::log1p(mu);
  for (float& v : out.values()) v = static_cast<float>(std::log1p(mu * v) * inv_log);
  return out;
}

const char* HdrNormalisationName(HdrNormalisation normalisation) {
  return normalisation == HdrNormalisation::kOwnMax ? "own_max" : "gt_max";
}

double MuPsnr(const Image& pred, const Image& gt, HdrNormalisation normalisation) {
  const auto [p, g] = RgbPair(pred, gt);
  const auto [mp, mg] = MuLawPair(p, g, normalisation);
  return PsnrOf(mp, mg, 1.0);
}

double MuSsim(const Image& pred, const Image& gt, HdrNormalisation normalisation) {
  const auto [p, g] = RgbPair(pred, gt);
  const auto [mp, mg] = MuLawPair(p, g, normalisation);
  return SsimOf(mp, mg, kSsimC1, kSsimC2);
}

// ---- PU21 ------------------------------------------------------------------------------------

double Pu21Encode(double luminance) {
  // std::clamp passes NaN through; the encoded NaN then fails the caller's finiteness checks.
  const double y = std::clamp(luminance, kPu21MinLuminance, kPu21MaxLuminance);
  const double yp = std::pow(y, kP4);
  const double v = kP7 * (std::pow((kP1 + kP2 * yp) / (1.0 + kP3 * yp), kP5) - kP6);
  return std::max(v, 0.0);
}

double Pu21Decode(double v) {
  static const double v_min = Pu21Encode(kPu21MinLuminance);
  static const double v_max = Pu21Encode(kPu21MaxLuminance);
  const double vc = std::clamp(v, v_min, v_max);
  const double vp = std::pow(std::max(vc / kP7 + kP6, 0.0), 1.0 / kP5);
  const double y = std::pow(std::max(vp - kP1, 0.0) / (kP2 - kP3 * vp), 1.0 / kP4);
  return std::clamp(y, kPu21MinLuminance, kPu21MaxLuminance);
}

double Luminance(double r, double g, double b) {
  return 0.212656 * r + 0.715158 * g + 0.072186 * b;
}

double Pu21Scale(const Image& gt) {
  if (gt.empty()) Fail("ground-truth image is empty ({})", gt.ShapeString());
  CheckFinite(gt, "ground-truth");
  return Pu21ScaleOfRgb(gt.Rgb());
}

double Pu21Psnr(const Image& pred, const Image& gt) {
  const auto [p, g] = RgbPair(pred, gt);
  const double scale = Pu21ScaleOfRgb(g);
  const auto encode = [scale](float x) { return Pu21Encode(scale * x); };
  return PsnrOf(MapValues(p, encode), MapValues(g, encode), kPu21Peak);
}

double Pu21Ssim(const Image& pred, const Image& gt) {
  const auto [p, g] = RgbPair(pred, gt);
  const double scale = Pu21ScaleOfRgb(g);
  Values lp = ScaledLuminance(p, scale);
  Values lg = ScaledLuminance(g, scale);
  for (Values* l : {&lp, &lg}) {
    ParallelFor(static_cast<std::int64_t>(l->v.size()), 16384,
                [l](std::int64_t i) { l->v[i] = Pu21Encode(l->v[i]); });
  }
  const double c1 = (0.01 * kPu21Peak) * (0.01 * kPu21Peak);
  const double c2 = (0.03 * kPu21Peak) * (0.03 * kPu21Peak);
  return SsimOf(lp, lg, c1, c2);
}

// ---- Bundles ---------------------------------------------------------------------------------

MetricList LdrMetrics(const Image& pred, const Image& gt) {
  CheckPair(pred, gt, "prediction", "ground truth");
  const Image p = pred.Rgb();
  const Image g = gt.Rgb();
  return {{"psnr", Psnr(p, g)}, {"psnr_channel_mean", PsnrChannelMean(p, g)}, {"ssim", Ssim(p, g)}};
}

MetricList HdrMetrics(const Image& pred, const Image& gt) {
  const auto [p, g] = RgbPair(pred, gt);
  MetricList out;
  for (HdrNormalisation n : {HdrNormalisation::kOwnMax, HdrNormalisation::kGtMax}) {
    const auto [mp, mg] = MuLawPair(p, g, n);
    const std::string suffix = n == HdrNormalisation::kOwnMax ? "" : "_gt_max";
    out.emplace_back("mu_psnr" + suffix, PsnrOf(mp, mg, 1.0));
    out.emplace_back("mu_ssim" + suffix, SsimOf(mp, mg, kSsimC1, kSsimC2));
  }
  out.emplace_back("pu21_psnr", Pu21Psnr(p, g));
  out.emplace_back("pu21_ssim", Pu21Ssim(p, g));
  return out;
}

}  // namespace hdr4d
