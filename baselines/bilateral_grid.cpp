#include "baselines/bilateral_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/util/error.h"
#include "core/util/parallel.h"

namespace hdr4d::baselines {
namespace {

// Gaussian of one cell, truncated at two cells (the tail beyond holds about 1% of the mass);
// unnormalised: the normalisation by S^T B S 1 cancels any scale.
constexpr int kRadius = 2;
constexpr double kKernel[2 * kRadius + 1] = {0.1353352832366127, 0.6065306597126334, 1.0,
                                             0.6065306597126334, 0.1353352832366127};

// Lower cell and fraction of a coordinate in cells, for a grid of `cells` (>= 2) along the axis.
template <typename T>
void Locate(double coordinate, int cells, std::int32_t* index, T* fraction) {
  int i = static_cast<int>(std::floor(coordinate));
  i = std::clamp(i, 0, cells - 2);
  *index = i;
  *fraction = T(std::clamp(coordinate - i, 0.0, 1.0));
}

// Blurs `lines` lines of `length` values spaced `stride` apart; line k starts at start(k).
template <typename T, typename Start>
void BlurLines(T* grid, std::int64_t lines, int length, std::int64_t stride, Start start) {
  ParallelForChunks(lines, 64, [&](std::int64_t begin, std::int64_t end) {
    std::vector<T> line(length);
    for (std::int64_t k = begin; k < end; ++k) {
      T* g = grid + start(k);
      for (int i = 0; i < length; ++i) line[i] = g[i * stride];
      for (int i = 0; i < length; ++i) {
        T sum = T(0);
        const int lo = std::max(-kRadius, -i), hi = std::min(kRadius, length - 1 - i);
        for (int d = lo; d <= hi; ++d) sum += T(kKernel[d + kRadius]) * line[i + d];
        g[i * stride] = sum;
      }
    }
  });
}

}  // namespace

template <typename T>
BilateralGrid<T>::BilateralGrid(
    const T* guide, int width, int height, double sigma_space, double sigma_range)
    : width_(width), height_(height) {
  HDR4D_CHECK(width > 0 && height > 0);
  HDR4D_CHECK(sigma_space > 0 && sigma_range > 0 && std::isfinite(sigma_space) &&
              std::isfinite(sigma_range));
  const std::int64_t pixels = std::int64_t(width) * height;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::int64_t p = 0; p < pixels; ++p) {
    const double g = double(guide[p]);
    if (std::isfinite(g)) {
      lo = std::min(lo, g);
      hi = std::max(hi, g);
    }
  }
  if (!(lo <= hi)) lo = hi = 0.0;  // no finite guide value at all
  nx_ = int(std::floor((width - 1) / sigma_space)) + 2;
  ny_ = int(std::floor((height - 1) / sigma_space)) + 2;
  nz_ = int(std::floor((hi - lo) / sigma_range)) + 2;
  ix_.resize(width);
  fx_.resize(width);
  for (int x = 0; x < width; ++x) Locate(x / sigma_space, nx_, &ix_[x], &fx_[x]);
  iy_.resize(height);
  fy_.resize(height);
  for (int y = 0; y < height; ++y) Locate(y / sigma_space, ny_, &iy_[y], &fy_[y]);
  // Rows are in increasing order of their lower cell: row_begin_[gy] is the first row at gy.
  row_begin_.assign(ny_ + 1, height);
  for (int y = height - 1; y >= 0; --y) row_begin_[iy_[y]] = y;
  for (int gy = ny_ - 1; gy >= 0; --gy)
    row_begin_[gy] = std::min(row_begin_[gy], row_begin_[gy + 1]);
  iz_.resize(pixels);
  fz_.resize(pixels);
  ParallelForChunks(pixels, 8192, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t p = begin; p < end; ++p) {
      const double g = double(guide[p]);
      Locate(std::isfinite(g) ? (g - lo) / sigma_range : 0.0, nz_, &iz_[p], &fz_[p]);
    }
  });
  const std::vector<T> ones(pixels, T(1));
  normaliser_.resize(pixels);
  SplatBlurSlice(ones.data(), normaliser_.data());
  // Each pixel's own splat comes back to it with weight >= sum of its squared trilinear weights
  // (>= 1/8), so the normaliser is positive.
  for (std::int64_t p = 0; p < pixels; ++p) HDR4D_CHECK(normaliser_[p] > T(0));
}

template <typename T>
void BilateralGrid<T>::SplatBlurSlice(const T* v, T* out) const {
  const std::int64_t slab = std::int64_t(nx_) * nz_;  // one grid row: x-major, z fastest
  std::vector<T> grid(std::size_t(ny_) * slab, T(0));
  // Splat, gathered per grid row so no two tasks write the same cell.
  ParallelForChunks(ny_, 1, [&](std::int64_t gy0, std::int64_t gy1) {
    for (std::int64_t gy = gy0; gy < gy1; ++gy) {
      T* row = grid.data() + gy * slab;
      const int y_begin = gy > 0 ? row_begin_[gy - 1] : row_begin_[0];
      const int y_end = row_begin_[gy + 1];
      for (int y = y_begin; y < y_end; ++y) {
        const T wy = iy_[y] == gy ? T(1) - fy_[y] : fy_[y];
        if (wy == T(0)) continue;
        for (int x = 0; x < width_; ++x) {
          const std::int64_t p = std::int64_t(y) * width_ + x;
          const T a = wy * v[p];
          T* cell = row + std::int64_t(ix_[x]) * nz_ + iz_[p];
          const T wx0 = T(1) - fx_[x], wx1 = fx_[x], wz0 = T(1) - fz_[p], wz1 = fz_[p];
          cell[0] += a * wx0 * wz0;
          cell[1] += a * wx0 * wz1;
          cell[nz_] += a * wx1 * wz0;
          cell[nz_ + 1] += a * wx1 * wz1;
        }
      }
    }
  });
  // Blur along z (contiguous), x, then y.
  BlurLines(grid.data(), std::int64_t(ny_) * nx_, nz_, 1, [&](std::int64_t k) { return k * nz_; });
  BlurLines(grid.data(), std::int64_t(ny_) * nz_, nx_, nz_,
            [&](std::int64_t k) { return (k / nz_) * slab + k % nz_; });
  BlurLines(grid.data(), slab, ny_, slab, [](std::int64_t k) { return k; });
  // Slice: each pixel reads its 8 cells with the splat's weights.
  ParallelForChunks(height_, 16, [&](std::int64_t y0, std::int64_t y1) {
    for (std::int64_t y = y0; y < y1; ++y) {
      const T* row0 = grid.data() + std::int64_t(iy_[y]) * slab;
      const T* row1 = row0 + slab;
      const T wy1 = fy_[y], wy0 = T(1) - wy1;
      for (int x = 0; x < width_; ++x) {
        const std::int64_t p = y * width_ + x;
        const std::int64_t o = std::int64_t(ix_[x]) * nz_ + iz_[p];
        const T wx0 = T(1) - fx_[x], wx1 = fx_[x], wz0 = T(1) - fz_[p], wz1 = fz_[p];
        auto plane = [&](const T* r) {
          return wx0 * (wz0 * r[o] + wz1 * r[o + 1]) +
                 wx1 * (wz0 * r[o + nz_] + wz1 * r[o + nz_ + 1]);
        };
        out[p] = wy0 * plane(row0) + wy1 * plane(row1);
      }
    }
  });
}

template <typename T>
void BilateralGrid<T>::Filter(const T* values, T* out) const {
  SplatBlurSlice(values, out);
  const std::int64_t pixels = std::int64_t(width_) * height_;
  for (std::int64_t p = 0; p < pixels; ++p) out[p] /= normaliser_[p];
}

template <typename T>
void BilateralGrid<T>::FilterBackward(const T* dL_dout, T* dL_dvalues) const {
  const std::int64_t pixels = std::int64_t(width_) * height_;
  std::vector<T> scaled(pixels);
  for (std::int64_t p = 0; p < pixels; ++p) scaled[p] = dL_dout[p] / normaliser_[p];
  SplatBlurSlice(scaled.data(), dL_dvalues);
}

template class BilateralGrid<float>;
template class BilateralGrid<double>;

}  // namespace hdr4d::baselines
