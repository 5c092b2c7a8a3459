#include "core/metrics/hdr_alignment.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/metrics/flip.h"
#include "core/util/error.h"

namespace hdr4d {

namespace {

double PixelLuminance(const Image& image, int x, int y) {
  if (image.channels() < 3) return image.at(x, y, 0);
  return Luminance(image.at(x, y, 0), image.at(x, y, 1), image.at(x, y, 2));
}

void CheckHdrPair(const Image& pred, const Image& gt, const std::vector<std::uint8_t>* mask) {
  if (pred.empty() || gt.empty()) Fail("HDR alignment: an image is empty");
  if (pred.width() != gt.width() || pred.height() != gt.height() ||
      pred.ColourChannelCount() != gt.ColourChannelCount()) {
    Fail("HDR alignment: prediction {} and ground truth {} differ in shape", pred.ShapeString(),
         gt.ShapeString());
  }
  const std::size_t pixels = std::size_t(gt.width()) * gt.height();
  if (mask && mask->size() != pixels) {
    Fail("HDR alignment: the mask has {} entries for {} pixels", mask->size(), pixels);
  }
  for (const Image* image : {&pred, &gt}) {
    const float* d = image->data();
    for (std::size_t i = 0; i < image->size(); ++i) {
      if (!std::isfinite(d[i])) {
        Fail("HDR alignment: the {} holds a non-finite value (value index {})",
             image == &pred ? "prediction" : "ground truth", i);
      }
    }
  }
}

// Positive and normal: the log of a denormal or of 0 says nothing about the shape.
bool NormalLuminance(double v) { return v >= std::numeric_limits<float>::min(); }

// The pixels AlignHdr keeps under `mask` (W x H, checked): true luminance positive and normal.
std::size_t KeptPixels(const Image& gt, const std::vector<std::uint8_t>& mask) {
  const int w = gt.width(), h = gt.height();
  if (mask.size() != std::size_t(w) * h)
    Fail("HDR alignment: the mask has {} entries for {} pixels", mask.size(), std::size_t(w) * h);
  std::size_t kept = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      kept += mask[std::size_t(y) * w + x] && NormalLuminance(PixelLuminance(gt, x, y)) ? 1 : 0;
  return kept;
}

// Whether one bracket measures pixel (x, y): no colour channel clipped, one above black.
bool BracketMeasures(const Image& ldr, int x, int y) {
  bool clipped = false, lit = false;
  for (int c = 0; c < ldr.ColourChannelCount(); ++c) {
    const float v = ldr.at(x, y, c);
    clipped = clipped || !(v < kBracketClipped);  // NaN counts as clipped
    lit = lit || v > kBracketBlack;
  }
  return !clipped && lit;
}

}  // namespace

std::vector<std::uint8_t> MeasurableInBrackets(const std::vector<Image>& brackets) {
  if (brackets.empty()) Fail("measurable pixels: no bracket images given");
  const int w = brackets[0].width(), h = brackets[0].height();
  std::vector<std::uint8_t> mask(std::size_t(w) * h, 0);
  for (const Image& ldr : brackets) {
    if (ldr.width() != w || ldr.height() != h) {
      Fail("measurable pixels: bracket images differ in size ({} vs {}x{})", ldr.ShapeString(), w,
           h);
    }
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        if (BracketMeasures(ldr, x, y)) mask[std::size_t(y) * w + x] = 1;
      }
    }
  }
  return mask;
}

std::vector<std::uint8_t> ReproducedInBrackets(const std::vector<Image>& truth,
                                               const std::vector<Image>& rendered) {
  if (truth.empty() || truth.size() != rendered.size()) {
    Fail("reproduced pixels: {} truth brackets and {} rendered ones (need the same, at least one)",
         truth.size(), rendered.size());
  }
  const int w = truth[0].width(), h = truth[0].height();
  std::vector<std::uint8_t> mask(std::size_t(w) * h, 0);
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const Image& gt = truth[i];
    const Image& pred = rendered[i];
    for (const Image* image : {&gt, &pred}) {
      if (image->width() != w || image->height() != h) {
        Fail("reproduced pixels: bracket images differ in size ({} vs {}x{})",
             image->ShapeString(), w, h);
      }
    }
    const int colours = std::min(std::min(gt.channels(), pred.channels()), 3);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        if (!BracketMeasures(gt, x, y)) continue;
        double brightest = 0;
        for (int c = 0; c < colours; ++c) brightest = std::max(brightest, double(gt.at(x, y, c)));
        if (brightest < kLdrFitLevel) continue;
        bool close = true;  // NaN in the render is not close
        for (int c = 0; c < colours; ++c) {
          close = close && std::fabs(double(pred.at(x, y, c)) - gt.at(x, y, c)) <=
                               kLdrFitRelative * brightest;
        }
        if (close) mask[std::size_t(y) * w + x] = 1;
      }
    }
  }
  return mask;
}

// True when the first n values are all the same number.
static bool AllEqual(const std::vector<double>& v, std::size_t n) {
  return std::all_of(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n),
                     [&](double x) { return x == v[0]; });
}

HdrAlignment AlignHdr(const Image& pred, const Image& gt, const std::vector<std::uint8_t>* mask) {
  CheckHdrPair(pred, gt, mask);
  const int w = gt.width(), h = gt.height();
  const auto normal = NormalLuminance;
  std::vector<double> g_lum, p_lum;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (mask && !(*mask)[std::size_t(y) * w + x]) continue;
      const double g = PixelLuminance(gt, x, y);
      if (!normal(g)) continue;
      g_lum.push_back(g);
      p_lum.push_back(PixelLuminance(pred, x, y));
    }
  }
  HdrAlignment a;
  a.total = std::size_t(w) * h;
  a.pixels = g_lum.size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  a.slope = a.corr = a.contrast = nan;
  if (a.pixels == 0) return a;

  // The factor: the median log ratio over the pixels where the prediction is positive too.
  std::vector<double> ratio;
  ratio.reserve(a.pixels);
  double darkest_gt = g_lum[0];
  for (std::size_t i = 0; i < a.pixels; ++i) {
    darkest_gt = std::min(darkest_gt, g_lum[i]);
    if (normal(p_lum[i])) ratio.push_back(std::log(g_lum[i]) - std::log(p_lum[i]));
  }
  if (!ratio.empty()) {
    // Median (the mean of the two middle values for an even count).
    const std::size_t mid = ratio.size() / 2;
    std::nth_element(ratio.begin(), ratio.begin() + mid, ratio.end());
    double median = ratio[mid];
    if (ratio.size() % 2 == 0)
      median = 0.5 * (median + *std::max_element(ratio.begin(), ratio.begin() + mid));
    a.scale = std::exp(std::clamp(median, -700.0, 700.0));
  }
  // A measured pixel the prediction renders more than kHoleFactor below the darkest measured
  // truth (after the factor) is a hole in the model and counts at that floor: a hole rendered
  // exactly black (a fixed black backdrop) and one rendered e^-15 (a learned dark backdrop) are
  // the same error, and neither may drop out of the diagnostics, which would flatter the black
  // one. Three decades below anything the brackets measured leaves room for a prediction with
  // more contrast than the truth (slope > 1), which stays as it is.
  constexpr double kHoleFactor = 1e-3;
  const double floor_log = std::log(darkest_gt * kHoleFactor) - std::log(a.scale);
  std::vector<double> log_gt(a.pixels), log_pred(a.pixels);
  for (std::size_t i = 0; i < a.pixels; ++i) {
    log_gt[i] = std::log(g_lum[i]);
    log_pred[i] = normal(p_lum[i]) ? std::max(std::log(p_lum[i]), floor_log) : floor_log;
  }

  if (a.pixels < 2) return a;
  double mean_g = 0, mean_p = 0;
  for (std::size_t i = 0; i < a.pixels; ++i) {
    mean_g += log_gt[i];
    mean_p += log_pred[i];
  }
  mean_g /= double(a.pixels);
  mean_p /= double(a.pixels);
  double sgg = 0, spp = 0, sgp = 0;
  for (std::size_t i = 0; i < a.pixels; ++i) {
    const double dg = log_gt[i] - mean_g, dp = log_pred[i] - mean_p;
    sgg += dg * dg;
    spp += dp * dp;
    sgp += dg * dp;
  }
  // A constant truth has no spread: its sum of squares is rounding (1e-30 gave a slope of 5.72
  // and a contrast of 1e15, issue 51 case 17), so it is taken as exactly zero.
  if (AllEqual(log_gt, a.pixels)) sgg = sgp = 0;
  a.sums = {sgg, spp, sgp};
  if (sgg > 0) a.slope = sgp / sgg;
  if (sgg > 0) a.contrast = std::sqrt(spp / sgg);
  // All at one value (every pixel a hole): no correlation, whatever the rounding of the mean.
  const bool flat = std::all_of(log_pred.begin(), log_pred.end(),
                                [&](double v) { return v == log_pred[0]; });
  if (sgg > 0 && spp > 0 && !flat) a.corr = sgp / std::sqrt(sgg * spp);
  return a;
}

MetricList AlignedHdrMetrics(const Image& pred,
                             const Image& gt,
                             const std::vector<std::uint8_t>* mask,
                             bool with_flip) {
  const HdrAlignment a = AlignHdr(pred, gt, mask);
  Image aligned = pred.Rgb();
  float* d = aligned.data();
  for (std::size_t i = 0; i < aligned.size(); ++i) {
    // Clamped to float range: a prediction far off in scale must not overflow to inf.
    d[i] = float(std::min(double(d[i]) * a.scale, double(std::numeric_limits<float>::max())));
  }
  const Image gt_rgb = gt.Rgb();
  MetricList out = {
      {"hdr_align_scale", a.scale},
      {"hdr_log_slope", a.slope},
      {"hdr_log_corr", a.corr},
      {"hdr_log_contrast", a.contrast},
      {"hdr_measured_fraction", a.total ? double(a.pixels) / double(a.total) : 0.0},
      {"mu_psnr_aligned", MuPsnr(aligned, gt_rgb, HdrNormalisation::kGtMax)},
      {"mu_ssim_aligned", MuSsim(aligned, gt_rgb, HdrNormalisation::kGtMax)},
      {"pu21_psnr_aligned", Pu21Psnr(aligned, gt_rgb)},
      {"pu21_ssim_aligned", Pu21Ssim(aligned, gt_rgb)},
  };
  if (with_flip) out.emplace_back("hdr_flip_aligned", HdrFlip(aligned, gt_rgb));
  return out;
}

PooledShape PoolLogShape(const std::vector<LogShapeSums>& images) {
  LogShapeSums total;
  for (const LogShapeSums& s : images) {
    total.gg += s.gg;
    total.pp += s.pp;
    total.gp += s.gp;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  PooledShape pooled{nan, nan};
  if (total.gg > 0) pooled.slope = total.gp / total.gg;
  if (total.gg > 0 && total.pp > 0) pooled.corr = total.gp / std::sqrt(total.gg * total.pp);
  return pooled;
}

MetricList LdrFitHdrShape(const Image& pred,
                          const Image& gt,
                          const std::vector<std::uint8_t>& measured,
                          const std::vector<std::uint8_t>& reproduced,
                          LogShapeSums* sums) {
  const HdrAlignment fit = AlignHdr(pred, gt, &reproduced);
  // Only the count of the measured pixels: their alignment is AlignedHdrMetrics' own.
  const std::size_t measured_pixels = KeptPixels(gt, measured);
  if (sums) *sums = fit.sums;
  return {
      {"hdr_log_slope_ldr_fit", fit.slope},
      {"hdr_log_corr_ldr_fit", fit.corr},
      {"hdr_ldr_fit_fraction", measured_pixels ? double(fit.pixels) / double(measured_pixels)
                                               : std::numeric_limits<double>::quiet_NaN()},
  };
}

void SetPooledLdrFitShape(const std::vector<LogShapeSums>& images, nlohmann::json* mean) {
  const PooledShape pooled = PoolLogShape(images);
  const auto set = [&](const char* key, double value) {
    if (std::isfinite(value)) {
      (*mean)[key] = value;
    } else {
      mean->erase(key);
    }
  };
  set("hdr_log_slope_ldr_fit", pooled.slope);
  set("hdr_log_corr_ldr_fit", pooled.corr);
}

std::string UndefinedMetricReason(const std::string& key) {
  if (key.rfind("hdr_log_corr", 0) == 0)
    return "undefined: fewer than 2 measured pixels, or the ground truth's or the prediction's "
           "log luminance is constant";
  if (key.rfind("hdr_log_", 0) == 0)
    return "undefined: fewer than 2 measured pixels, or the ground truth's log luminance is "
           "constant (no spread to compare against)";
  return "undefined for this pair";
}

}  // namespace hdr4d
