#include "method/train/hdr_loss.h"

#include <algorithm>
#include <cmath>

#include "core/util/error.h"
#include "core/util/parallel.h"
#include "method/train/loss.h"

namespace hdr4d::method {

namespace {

constexpr std::int64_t kGrain = 8192;
constexpr std::size_t kAlignSample = 1 << 16;  // values in the median of HdrAlignScale
constexpr double kMaxLogAlign = 30.0;           // |log scale| at most: e^30 ~ 1e13

}  // namespace

double HdrAlignScale(const std::vector<float>& hdr,
                     const float* hdr_mu_gt,
                     double mu,
                     std::vector<double>* ratios_buffer) {
  // A regular sample keeps the median's cost bounded on large images; 3 is avoided in the stride
  // so that every channel is sampled.
  const std::size_t stride = std::max<std::size_t>(1, hdr.size() / kAlignSample) | 1;
  const std::size_t step = stride % 3 == 0 ? stride + 2 : stride;
  std::vector<double>& ratios = *ratios_buffer;
  ratios.clear();
  for (std::size_t i = 0; i < hdr.size(); i += step) {
    const double target = MuLawDecode(static_cast<double>(hdr_mu_gt[i]), mu);
    // Values the encoding resolves and the render has: the black of a target (or a render that
    // has not reached a pixel yet) says nothing about the scale.
    if (target > 1.0 / mu && hdr[i] > 0.0f && std::isfinite(hdr[i]))
      ratios.push_back(std::log(target) - std::log(static_cast<double>(hdr[i])));
  }
  if (ratios.empty()) return 1.0;
  auto mid = ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2);
  std::nth_element(ratios.begin(), mid, ratios.end());
  // Clamped so that one bad view cannot send the term to an overflow.
  return std::exp(std::clamp(*mid, -kMaxLogAlign, kMaxLogAlign));
}

double AddHdrTerm(const std::vector<float>& hdr,
                  const float* hdr_mu_gt,
                  int width,
                  int height,
                  int channels,
                  const SupervisionTerms& terms,
                  double scale,
                  HdrLossScratch* s,
                  float* dL_draster) {
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  const std::size_t values = pixels * 3;
  const float k = static_cast<float>(scale);
  s->target.resize(values);
  s->grad.resize(values);
  const MuLawCoder<float> coder(terms.hdr_mu);
  ParallelFor(static_cast<std::int64_t>(values), kGrain,
              [&](std::int64_t i) { s->target[i] = coder.Encode(k * hdr[i]); });
  const double loss = PhotometricLoss(s->target.data(), hdr_mu_gt, width, height, 3,
                                      terms.lambda_dssim, s->grad.data())
                          .value;
  // The scale is a constant of the view (a stop-gradient): d mu(k x) / dx = k mu'(k x).
  const float w = terms.hdr_weight * k;
  ParallelFor(static_cast<std::int64_t>(pixels), kGrain, [&](std::int64_t p) {
    for (int c = 0; c < 3; ++c) {
      dL_draster[p * channels + c] +=
          w * coder.EncodeBackward(k * hdr[p * 3 + c], s->grad[p * 3 + c]);
    }
  });
  return loss;
}

FrameLoss HdrFrameLoss(const float* raster,
                       int channels,
                       int width,
                       int height,
                       const float* ldr_gt,
                       const float* hdr_mu_gt,
                       ToneMapper* tone_mapper,
                       const SupervisionTerms& terms,
                       HdrLossScratch* s,
                       float* dL_draster,
                       float* dL_draster_geometry) {
  HDR4D_CHECK(channels == 3 || channels == 6);
  HDR4D_CHECK(!terms.ldr_gaussian || channels == 6);
  HDR4D_CHECK(!terms.ldr_pixel || tone_mapper != nullptr);
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  const std::size_t values = pixels * 3;
  std::fill(dL_draster, dL_draster + pixels * channels, 0.0f);
  FrameLoss loss;
  ExtractChannels(raster, channels, 0, pixels, &s->hdr);
  s->grad.resize(values);

  // 3D branch: the tone-mapped Gaussians, clamped to [0,1] as the reference does.
  if (terms.ldr_gaussian) {
    ExtractChannels(raster, channels, 3, pixels, &s->ldr);
    for (float& v : s->ldr) v = std::clamp(v, 0.0f, 1.0f);
    loss.ldr_gaussian =
        PhotometricLoss(s->ldr.data(), ldr_gt, width, height, 3, terms.lambda_dssim, s->grad.data())
            .value;
    ParallelFor(static_cast<std::int64_t>(pixels), kGrain, [&](std::int64_t p) {
      for (int c = 0; c < 3; ++c) {
        const float v = raster[p * channels + 3 + c];
        // The clamp passes the gradient inside [0,1] only.
        dL_draster[p * channels + 3 + c] = (v >= 0.0f && v <= 1.0f) ? s->grad[p * 3 + c] : 0.0f;
      }
    });
  }

  // 2D branch: the same tone curves per pixel on the HDR raster.
  if (terms.ldr_pixel) {
    PixelLogImage(s->hdr, terms.pixel_log_epsilon, &s->x);
    s->pixel_ldr.resize(values);
    tone_mapper->MapImage(s->x.data(), width, height, s->pixel_ldr.data());
    loss.ldr_pixel = PhotometricLoss(s->pixel_ldr.data(), ldr_gt, width, height, 3,
                                     terms.lambda_dssim, s->grad.data())
                         .value;
    s->dx.resize(values);
    tone_mapper->MapImageBackward(s->x.data(), width, height, s->grad.data(), s->dx.data());
    ParallelFor(static_cast<std::int64_t>(pixels), kGrain, [&](std::int64_t p) {
      for (int c = 0; c < 3; ++c) {
        dL_draster[p * channels + c] +=
            PixelLogBackward(s->hdr[p * 3 + c], s->dx[p * 3 + c], terms.pixel_log_epsilon);
      }
    });
  }

  // HDR term on the mu-law of the raw HDR raster (scaled per view under --hdr-target aligned).
  if (terms.hdr && hdr_mu_gt) {
    if (!terms.hdr_geometry && dL_draster_geometry != nullptr) {
      std::copy(dL_draster, dL_draster + pixels * channels, dL_draster_geometry);
      loss.geometry_split = true;
    }
    loss.hdr_scale =
        terms.hdr_align ? HdrAlignScale(s->hdr, hdr_mu_gt, terms.hdr_mu, &s->ratios) : 1.0;
    loss.hdr = AddHdrTerm(s->hdr, hdr_mu_gt, width, height, channels, terms, loss.hdr_scale, s,
                          dL_draster);
  }
  loss.total = loss.ldr_gaussian + loss.ldr_pixel + terms.hdr_weight * loss.hdr;
  return loss;
}

}  // namespace hdr4d::method
