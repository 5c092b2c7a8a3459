// The photometric loss and its backward. The kernels are plain loops that the compiler
// vectorises; Highway compiles them once per x86 target (AVX-512, AVX2 and the baseline) and
// picks the best one at run time, which halves the time against the SSE2-only baseline.
#include "method/train/loss.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/util/error.h"
#include "core/metrics/metrics.h"
#include "core/util/parallel.h"

// SSSE3 / SSE4 gain little over the SSE2 baseline for these loops; skipping them keeps the
// build short.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "method/train/loss.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

// ---- Target-independent helpers (compiled once) ----------------------------------------------
#ifndef HDR4D_METHOD_LOSS_COMMON_
#define HDR4D_METHOD_LOSS_COMMON_
namespace hdr4d::method::loss_detail {

constexpr int kRadius = kSsimWindow / 2;

// The SSIM window of core/metrics/metrics.h, rounded once to T.
template <typename T>
const std::array<T, kSsimWindow>& Window() {
  static const std::array<T, kSsimWindow> window = [] {
    const std::array<double, kSsimWindow> g = SsimGaussianKernel();
    std::array<T, kSsimWindow> out{};
    for (int k = 0; k < kSsimWindow; ++k) out[k] = static_cast<T>(g[k]);
    return out;
  }();
  return window;
}

// Working memory reused across calls: one buffer of image-sized maps per calling thread, and
// one buffer of row scratch per worker thread.
template <typename T>
T* Workspace(std::size_t size) {
  thread_local std::vector<T> workspace;
  if (workspace.size() < size) workspace.resize(size);
  return workspace.data();
}
// Row scratch starts on a cache line (the filters' rows are padded to whole lines, so their
// vector loads and stores never straddle two).
template <typename T>
T* RowScratch(std::size_t size) {
  constexpr std::size_t kSlack = 64 / sizeof(T);
  thread_local std::vector<T> scratch;
  if (scratch.size() < size + kSlack) scratch.resize(size + kSlack);
  const auto address = reinterpret_cast<std::uintptr_t>(scratch.data());
  return scratch.data() + ((64 - address % 64) % 64) / sizeof(T);
}
// n rounded up to whole cache lines of T.
template <typename T>
std::size_t LinePitch(std::size_t n) {
  constexpr std::size_t k = 64 / sizeof(T);
  return (n + k - 1) / k * k;
}

}  // namespace hdr4d::method::loss_detail
#endif  // HDR4D_METHOD_LOSS_COMMON_

// ---- Kernels, once per target ------------------------------------------------------------------
HWY_BEFORE_NAMESPACE();
namespace hdr4d::method {
namespace HWY_NAMESPACE {
namespace {

using loss_detail::kRadius;
using loss_detail::LinePitch;
using loss_detail::RowScratch;
using loss_detail::Window;
using loss_detail::Workspace;

// dst[j] = sum_k g[k] src[k][j] for the 11 taps, using the window's symmetry (g[5-k] = g[5+k]).
// Horizontal pass: src[k] = padded row + k * stride; vertical pass: src[k] = row y + k - 5, or a
// zero row outside the image. Both are zero padding.
template <typename T>
void Taps(const T* const* src, T* __restrict dst, std::size_t len) {
  const auto& g = Window<T>();
  const T w0 = g[5], w1 = g[6], w2 = g[7], w3 = g[8], w4 = g[9], w5 = g[10];
  const T* __restrict s0 = src[0];
  const T* __restrict s1 = src[1];
  const T* __restrict s2 = src[2];
  const T* __restrict s3 = src[3];
  const T* __restrict s4 = src[4];
  const T* __restrict s5 = src[5];
  const T* __restrict s6 = src[6];
  const T* __restrict s7 = src[7];
  const T* __restrict s8 = src[8];
  const T* __restrict s9 = src[9];
  const T* __restrict s10 = src[10];
  for (std::size_t j = 0; j < len; ++j) {
    dst[j] = w0 * s5[j] + w1 * (s4[j] + s6[j]) + w2 * (s3[j] + s7[j]) + w3 * (s2[j] + s8[j]) +
             w4 * (s1[j] + s9[j]) + w5 * (s0[j] + s10[j]);
  }
}

// Horizontal filtering of a row stored with kRadius * stride zeros on each side.
template <typename T>
void FilterPaddedRow(const T* padded, T* dst, std::size_t len, std::size_t stride) {
  const T* src[kSsimWindow];
  for (int k = 0; k < kSsimWindow; ++k) src[k] = padded + static_cast<std::size_t>(k) * stride;
  Taps(src, dst, len);
}

// Sums in double over 8 fixed lanes, then the lanes in order: vectorisable and deterministic.
constexpr int kLanes = 8;
template <typename T>
double SumRow(const T* v, std::size_t len) {
  double lanes[kLanes] = {};
  std::size_t j = 0;
  for (; j + kLanes <= len; j += kLanes) {
    for (int l = 0; l < kLanes; ++l) lanes[l] += static_cast<double>(v[j + l]);
  }
  for (int l = 0; j < len; ++j, ++l) lanes[l] += static_cast<double>(v[j]);
  double sum = 0.0;
  for (double s : lanes) sum += s;
  return sum;
}
template <typename T>
double SumAbsDiffRow(const T* a, const T* b, std::size_t len) {
  double lanes[kLanes] = {};
  std::size_t j = 0;
  for (; j + kLanes <= len; j += kLanes) {
    for (int l = 0; l < kLanes; ++l) {
      lanes[l] += std::abs(static_cast<double>(a[j + l]) - static_cast<double>(b[j + l]));
    }
  }
  for (int l = 0; j < len; ++j, ++l) {
    lanes[l] += std::abs(static_cast<double>(a[j]) - static_cast<double>(b[j]));
  }
  double sum = 0.0;
  for (double s : lanes) sum += s;
  return sum;
}

// The five per-pixel quantities of SSIM's window sums. Restrict-qualified parameters: GCC does
// not apply __restrict to local pointers for its alias analysis, and with five output rows the
// loop needs more run-time overlap checks than it will emit, so it stayed scalar.
template <typename T>
void WindowProducts(const T* __restrict a, const T* __restrict b, T* __restrict qx,
                    T* __restrict qy, T* __restrict qxx, T* __restrict qyy, T* __restrict qxy,
                    std::size_t len) {
  for (std::size_t j = 0; j < len; ++j) {
    qx[j] = a[j];
    qy[j] = b[j];
    qxx[j] = a[j] * a[j];
    qyy[j] = b[j] * b[j];
    qxy[j] = a[j] * b[j];
  }
}

// The SSIM of one value from its window sums: S = (a1 a2) / (b1 b2), with the luminance (a1, b1)
// and contrast-structure (a2, b2) terms kept for the partials.
template <typename T>
struct SsimTerms {
  T a1, a2, b1, b2;
};
template <typename T>
inline SsimTerms<T> WindowSsim(T mx, T my, T e_xx, T e_yy, T e_xy, T c1, T c2) {
  return {T(2) * mx * my + c1, T(2) * (e_xy - mx * my) + c2, mx * mx + my * my + c1,
          (e_xx - mx * mx) + (e_yy - my * my) + c2};
}

// One row of the SSIM map from the filtered sums, and its partials with respect to the sums of
// the prediction (mu_x, E[x^2], E[xy]) scaled by `scale`: dS/dmu_x (directly and through
// var_x = E[x^2] - mu_x^2 and cov = E[xy] - mu_x mu_y), dS/dE[x^2] = -S / b2 and
// dS/dE[xy] = 2 a1 / (b1 b2). A function of its own for the reason of WindowProducts.
template <typename T>
void SsimRowWithPartials(const T* __restrict mu_x, const T* __restrict mu_y,
                         const T* __restrict e_xx, const T* __restrict e_yy,
                         const T* __restrict e_xy, T* __restrict ssim, T* __restrict p_mu,
                         T* __restrict p_xx, T* __restrict p_xy, std::size_t len, T c1, T c2,
                         T scale) {
  for (std::size_t j = 0; j < len; ++j) {
    const T mx = mu_x[j], my = mu_y[j];
    const auto [a1, a2, b1, b2] = WindowSsim(mx, my, e_xx[j], e_yy[j], e_xy[j], c1, c2);
    const T inv = T(1) / (b1 * b2);
    const T s = a1 * a2 * inv;
    ssim[j] = s;
    const T inv_b1 = b2 * inv;
    const T inv_b2 = b1 * inv;
    p_mu[j] = scale * (T(2) * my * (a2 - a1) * inv + T(2) * mx * s * (inv_b2 - inv_b1));
    p_xx[j] = scale * (-s * inv_b2);
    p_xy[j] = scale * (T(2) * a1 * inv);
  }
}

// The horizontally filtered rows of `maps` image-sized maps that the vertical taps at a row need:
// a ring of kSsimWindow rows per map (image row r at slot r mod kSsimWindow, rows whole cache
// lines apart), filled in row order as a band of rows advances. The vertical taps
// are the same taps on the same values as filtering whole planes, so the banding changes no result.
template <typename T>
class FilteredRowRing {
 public:
  // The ring and `maps` output rows of `len` values, in the calling thread's row scratch after
  // `extra` values of the caller's own (at the scratch's start, returned by Extra(); rounded up
  // to whole lines so that the ring stays aligned), for a band starting at `first_row`.
  FilteredRowRing(int maps, std::size_t len, std::size_t extra, std::int64_t first_row)
      : maps_(maps),
        len_(len),
        line_(LinePitch<T>(len)),
        ring_len_(static_cast<std::size_t>(kSsimWindow) * line_),
        extra_lines_(LinePitch<T>(extra)),
        next_(std::max<std::int64_t>(0, first_row - kRadius)),
        base_(RowScratch<T>(extra_lines_ + static_cast<std::size_t>(maps) * (ring_len_ + line_))) {}
  T* Extra() const { return base_; }
  // Output row q of the last Filter call.
  T* Out(int q) const { return base_ + extra_lines_ + maps_ * ring_len_ + q * line_; }
  // Calls fill(r, dst) for each row r not yet filled up to row y + kRadius (below `height`),
  // where dst(q) is map q's ring slot for that row, to be filled with its horizontal filtering.
  template <typename Fill>
  void FillFor(std::int64_t y, int height, Fill&& fill) {
    const std::int64_t last = std::min<std::int64_t>(height - 1, y + kRadius);
    for (; next_ <= last; ++next_) {
      const std::size_t slot = static_cast<std::size_t>(next_ % kSsimWindow) * line_;
      fill(next_, [&](int q) { return base_ + extra_lines_ + q * ring_len_ + slot; });
    }
  }
  // The vertical taps at row y of every map into Out(q); rows outside the image read `zeros`.
  void Filter(const T* zeros, std::int64_t y, int height) const {
    for (int q = 0; q < maps_; ++q) {
      const T* ring = base_ + extra_lines_ + q * ring_len_;
      const T* src[kSsimWindow];
      for (int k = 0; k < kSsimWindow; ++k) {
        const std::int64_t r = y + k - kRadius;
        src[k] = (r >= 0 && r < height) ? ring + static_cast<std::size_t>(r % kSsimWindow) * line_
                                        : zeros;
      }
      Taps(src, Out(q), len_);
    }
  }

 private:
  int maps_;
  std::size_t len_, line_, ring_len_, extra_lines_;
  std::int64_t next_;
  T* base_;
};

// Rows per band of the separable filters. Each band filters its rows horizontally into a ring of
// kSsimWindow rows as the vertical filter needs them (so both passes read from L1/L2 instead of
// whole filtered planes from memory: 5 maps of a 400x400x3 image are 9.6 MB), at the cost of
// filtering the 2 x kRadius rows around a band twice; a few bands per thread keep that small and
// the threads balanced. Bands change no value, only where it is computed.
inline std::int64_t BandRows(int height) {
  const std::int64_t bands = 2 * static_cast<std::int64_t>(std::max(1, MaxThreads()));
  return std::max<std::int64_t>(3 * kSsimWindow, (height + bands - 1) / bands);
}

// The sizes of one loss call: rows of width x channels values, zero-padded by kRadius pixels on
// each side in the maps the filters read, and the bands the passes run in parallel.
struct LossLayout {
  LossLayout(int width, int height_, int channels)
      : stride(static_cast<std::size_t>(channels)),
        row_len(static_cast<std::size_t>(width) * stride),
        pad(static_cast<std::size_t>(kRadius) * stride),
        pitch(row_len + 2 * pad),
        padded_plane(pitch * static_cast<std::size_t>(height_)),
        height(height_),
        band(BandRows(height_)) {}
  std::size_t stride, row_len, pad;
  std::size_t pitch;         // a zero-padded row
  std::size_t padded_plane;  // a map of zero-padded rows
  int height;
  std::int64_t band;
};

// Pass 1 over rows [y0, y1): the five quantities of each row in padded scratch rows, filtered
// horizontally into the ring; per row, the vertical filtering, the SSIM map's row sum
// (ssim_rows) and the L1 row sum (l1_rows); with `partials` (the backward), the scaled partials
// P_mu, P_xx, P_xy of each row into those three padded maps.
template <typename T>
void SsimBand(const T* pred,
              const T* gt,
              const LossLayout& L,
              const T* zeros,
              T* partials,
              T scale,
              std::int64_t y0,
              std::int64_t y1,
              double* l1_rows,
              double* ssim_rows) {
  const T c1 = static_cast<T>(kSsimC1);
  const T c2 = static_cast<T>(kSsimC2);
  const std::size_t row_len = L.row_len, pitch = L.pitch, pad = L.pad;
  const int height = L.height;
  // The caller's part of the scratch: the SSIM map's row, then the five padded product rows.
  const std::size_t ssim_len = LinePitch<T>(row_len);
  FilteredRowRing<T> ring(5, row_len, ssim_len + 5 * pitch, y0);
  T* __restrict ssim = ring.Extra();
  T* scratch = ssim + ssim_len;
  std::fill(scratch, scratch + 5 * pitch, T(0));
  T* qx = scratch + pad;
  T* qy = qx + pitch;
  T* qxx = qy + pitch;
  T* qyy = qxx + pitch;
  T* qxy = qyy + pitch;
  T* __restrict mu_x = ring.Out(0);
  T* __restrict mu_y = ring.Out(1);
  T* __restrict e_xx = ring.Out(2);
  T* __restrict e_yy = ring.Out(3);
  T* __restrict e_xy = ring.Out(4);
  for (std::int64_t y = y0; y < y1; ++y) {
    ring.FillFor(y, height, [&](std::int64_t r, auto dst) {
      const std::size_t base = static_cast<std::size_t>(r) * row_len;
      const T* __restrict a = pred + base;
      const T* __restrict b = gt + base;
      WindowProducts(a, b, qx, qy, qxx, qyy, qxy, row_len);
      if (r >= y0 && r < y1) l1_rows[r] = SumAbsDiffRow(a, b, row_len);
      for (int q = 0; q < 5; ++q) FilterPaddedRow(scratch + q * pitch, dst(q), row_len, L.stride);
    });
    ring.Filter(zeros, y, height);
    if (partials) {
      T* row[3];
      for (int q = 0; q < 3; ++q) {
        T* r = partials + static_cast<std::size_t>(q) * L.padded_plane +
               static_cast<std::size_t>(y) * pitch;
        std::fill(r, r + pad, T(0));
        std::fill(r + pad + row_len, r + pitch, T(0));
        row[q] = r + pad;
      }
      SsimRowWithPartials(mu_x, mu_y, e_xx, e_yy, e_xy, ssim, row[0], row[1], row[2], row_len,
                          c1, c2, scale);
    } else {
      for (std::size_t j = 0; j < row_len; ++j) {
        const auto [a1, a2, b1, b2] =
            WindowSsim(mu_x[j], mu_y[j], e_xx[j], e_yy[j], e_xy[j], c1, c2);
        ssim[j] = a1 * a2 * (T(1) / (b1 * b2));
      }
    }
    ssim_rows[y] = SumRow(ssim, row_len);
  }
}

// Pass 2 over rows [y0, y1): the three partial maps filtered horizontally into the ring, then
// per row the vertical filtering and the chain rule into the gradient.
template <typename T>
void GradientBand(const T* pred,
                  const T* gt,
                  const LossLayout& L,
                  const T* zeros,
                  const T* partials,
                  T l1_weight,
                  std::int64_t y0,
                  std::int64_t y1,
                  T* grad) {
  const std::size_t row_len = L.row_len;
  FilteredRowRing<T> ring(3, row_len, 0, y0);
  const T* __restrict g_mu = ring.Out(0);
  const T* __restrict g_xx = ring.Out(1);
  const T* __restrict g_xy = ring.Out(2);
  for (std::int64_t y = y0; y < y1; ++y) {
    ring.FillFor(y, L.height, [&](std::int64_t r, auto dst) {
      for (int q = 0; q < 3; ++q) {
        FilterPaddedRow(partials + static_cast<std::size_t>(q) * L.padded_plane +
                            static_cast<std::size_t>(r) * L.pitch,
                        dst(q), row_len, L.stride);
      }
    });
    ring.Filter(zeros, y, L.height);
    const std::size_t base = static_cast<std::size_t>(y) * row_len;
    const T* __restrict a = pred + base;
    const T* __restrict b = gt + base;
    T* __restrict out = grad + base;
    for (std::size_t j = 0; j < row_len; ++j) {
      const T d = a[j] - b[j];
      const T sign = (d > T(0) ? T(1) : T(0)) - (d < T(0) ? T(1) : T(0));  // sign(0) = 0
      out[j] = l1_weight * sign + g_mu[j] + T(2) * a[j] * g_xx[j] + b[j] * g_xy[j];
    }
  }
}

template <typename T>
LossResult LossImpl(
    const T* pred, const T* gt, int width, int height, int channels, T lambda, T* grad) {
  HDR4D_CHECK(width > 0 && height > 0 && channels > 0);
  HDR4D_CHECK(lambda >= T(0) && lambda <= T(1));
  const LossLayout L(width, height, channels);
  const double count = static_cast<double>(L.row_len * static_cast<std::size_t>(height));
  const bool backward = grad != nullptr;
  // Layout: a zero row, then, for the backward, the per-pixel partials P_mu, P_xx, P_xy in
  // zero-padded rows (the only image-sized maps: the backward's bands need their neighbours'
  // rows).
  T* work = Workspace<T>(L.row_len + (backward ? 3 * L.padded_plane : 0));
  T* zeros = work;
  std::fill(zeros, zeros + L.row_len, T(0));
  T* partials = backward ? work + L.row_len : nullptr;
  std::vector<double> l1_rows(height), ssim_rows(height);
  // d value / d mean(SSIM) = -lambda, and the mean divides by the count.
  const T scale = static_cast<T>(-static_cast<double>(lambda) / count);
  ParallelForChunks(height, L.band, [&](std::int64_t y0, std::int64_t y1) {
    SsimBand(pred, gt, L, zeros, partials, scale, y0, y1, l1_rows.data(), ssim_rows.data());
  });

  LossResult result;
  double l1 = 0.0, ssim = 0.0;
  for (int y = 0; y < height; ++y) {
    l1 += l1_rows[y];
    ssim += ssim_rows[y];
  }
  result.l1 = l1 / count;
  result.ssim = ssim / count;
  result.value = (1.0 - static_cast<double>(lambda)) * result.l1 +
                 static_cast<double>(lambda) * (1.0 - result.ssim);
  if (!backward) return result;

  const T l1_weight = static_cast<T>((1.0 - static_cast<double>(lambda)) / count);
  ParallelForChunks(height, L.band, [&](std::int64_t y0, std::int64_t y1) {
    GradientBand(pred, gt, L, zeros, partials, l1_weight, y0, y1, grad);
  });
  return result;
}

}  // namespace

LossResult LossFloat(const float* pred,
                     const float* gt,
                     int width,
                     int height,
                     int channels,
                     float lambda,
                     float* grad) {
  return LossImpl<float>(pred, gt, width, height, channels, lambda, grad);
}

#if HWY_TARGET == HWY_STATIC_TARGET
// The double path serves tests and references only: one (baseline) build is enough.
LossResult LossDouble(const double* pred,
                      const double* gt,
                      int width,
                      int height,
                      int channels,
                      double lambda,
                      double* grad) {
  return LossImpl<double>(pred, gt, width, height, channels, lambda, grad);
}
#endif

}  // namespace HWY_NAMESPACE
}  // namespace hdr4d::method
HWY_AFTER_NAMESPACE();

// ---- Public entry points
// -------------------------------------------------------------------------
#if HWY_ONCE
namespace hdr4d::method {

HWY_EXPORT(LossFloat);

LossResult PhotometricLoss(const float* pred,
                           const float* gt,
                           int width,
                           int height,
                           int channels,
                           float lambda_dssim,
                           float* dL_dpred) {
  return HWY_DYNAMIC_DISPATCH(LossFloat)(pred, gt, width, height, channels, lambda_dssim, dL_dpred);
}

LossResult PhotometricLoss(const double* pred,
                           const double* gt,
                           int width,
                           int height,
                           int channels,
                           double lambda_dssim,
                           double* dL_dpred) {
  return HWY_STATIC_DISPATCH(LossDouble)(pred, gt, width, height, channels, lambda_dssim, dL_dpred);
}

}  // namespace hdr4d::method
#endif  // HWY_ONCE
