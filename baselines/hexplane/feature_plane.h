// One feature plane of HexPlane (Cao & Johnson 2023): a height x width grid of `comps` features,
// read by bilinear interpolation with PyTorch grid_sample's align_corners=True convention (the
// reference's): coordinate -1 is the first grid point, +1 the last. Stored channel-last
// ([y][x][c]) so one lookup reads each corner's features contiguously. Coordinates are treated
// as constants (the reference detaches them), so the backward only scatter-adds into the plane.
//
// Templated on the scalar: training runs in float, the finite-difference tests in double.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace hdr4d::baselines::hexplane {

template <typename T>
struct Plane {
  int comps = 0, height = 0, width = 0;
  std::vector<T> data;  // height x width x comps

  Plane() = default;
  Plane(int c, int h, int w) : comps(c), height(h), width(w), data(std::size_t(c) * h * w, T(0)) {}
  std::size_t size() const { return data.size(); }
};

// The four corners of one lookup: cell indices (y * width + x) and their bilinear weights.
template <typename T>
struct BilinearTap {
  int cell[4];
  T weight[4];
};

// u runs along the width, v along the height, both in [-1, 1] (clamped: a point on the border
// reads the border, as the reference's in-box samples do). Needs width, height >= 2.
template <typename T>
BilinearTap<T> MakeTap(const Plane<T>& p, T u, T v) {
  const T fx = std::clamp((u + T(1)) * T(0.5) * T(p.width - 1), T(0), T(p.width - 1));
  const T fy = std::clamp((v + T(1)) * T(0.5) * T(p.height - 1), T(0), T(p.height - 1));
  const int x0 = std::min(static_cast<int>(fx), p.width - 2);
  const int y0 = std::min(static_cast<int>(fy), p.height - 2);
  const T tx = fx - T(x0), ty = fy - T(y0);
  BilinearTap<T> t;
  t.cell[0] = y0 * p.width + x0;
  t.cell[1] = t.cell[0] + 1;
  t.cell[2] = t.cell[0] + p.width;
  t.cell[3] = t.cell[2] + 1;
  t.weight[0] = (T(1) - tx) * (T(1) - ty);
  t.weight[1] = tx * (T(1) - ty);
  t.weight[2] = (T(1) - tx) * ty;
  t.weight[3] = tx * ty;
  return t;
}

// out[c] = sum over corners of weight * feature[c].
template <typename T>
void Gather(const Plane<T>& p, const BilinearTap<T>& t, T* out) {
  const int n = p.comps;
  std::fill(out, out + n, T(0));
  for (int k = 0; k < 4; ++k) {
    const T* f = p.data.data() + std::size_t(t.cell[k]) * n;
    const T w = t.weight[k];
    for (int c = 0; c < n; ++c) out[c] += w * f[c];
  }
}

// Backward of Gather: grad[corner][c] += weight * dL_dout[c].
template <typename T>
void Scatter(const BilinearTap<T>& t, const T* dL_dout, Plane<T>* grad) {
  const int n = grad->comps;
  for (int k = 0; k < 4; ++k) {
    T* g = grad->data.data() + std::size_t(t.cell[k]) * n;
    const T w = t.weight[k];
    for (int c = 0; c < n; ++c) g[c] += w * dL_dout[c];
  }
}

// The plane resampled to height x width by bilinear interpolation with aligned corners (the
// reference's F.interpolate(mode="bilinear", align_corners=True) when it upsamples).
template <typename T>
Plane<T> Resized(const Plane<T>& p, int height, int width) {
  Plane<T> out(p.comps, height, width);
  for (int y = 0; y < height; ++y) {
    const T v = height > 1 ? T(2) * y / (height - 1) - T(1) : T(0);
    for (int x = 0; x < width; ++x) {
      const T u = width > 1 ? T(2) * x / (width - 1) - T(1) : T(0);
      Gather(p, MakeTap(p, u, v), out.data.data() + (std::size_t(y) * width + x) * p.comps);
    }
  }
  return out;
}

// The reference's TVLoss on one plane (batch 1): 2 (h_w * sum dv^2 / count_v + w_w * sum du^2 /
// count_u), where dv differences neighbours along the height and du along the width, and each
// count is the number of differences. Adds scale * dTV/dplane to *grad (may be null).
template <typename T>
T TotalVariation(const Plane<T>& p, T height_weight, T width_weight, T scale, Plane<T>* grad) {
  const int n = p.comps, h = p.height, w = p.width;
  const T count_v = T(std::max(1, n * (h - 1) * w)), count_u = T(std::max(1, n * h * (w - 1)));
  const T kv = T(2) * height_weight / count_v, ku = T(2) * width_weight / count_u;
  T sum_v = 0, sum_u = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const T* a = p.data.data() + (std::size_t(y) * w + x) * n;
      for (int c = 0; c < n; ++c) {
        if (y + 1 < h) {
          const T d = a[std::size_t(w) * n + c] - a[c];
          sum_v += d * d;
          if (grad) {
            T* g = grad->data.data() + (std::size_t(y) * w + x) * n;
            g[c] -= scale * kv * T(2) * d;
            g[std::size_t(w) * n + c] += scale * kv * T(2) * d;
          }
        }
        if (x + 1 < w) {
          const T d = a[n + c] - a[c];
          sum_u += d * d;
          if (grad) {
            T* g = grad->data.data() + (std::size_t(y) * w + x) * n;
            g[c] -= scale * ku * T(2) * d;
            g[n + c] += scale * ku * T(2) * d;
          }
        }
      }
    }
  }
  return kv * sum_v + ku * sum_u;
}

// The reference's L1 term on one plane: mean |value|. Adds scale * its subgradient (sign) to *grad.
template <typename T>
T MeanAbs(const Plane<T>& p, T scale, Plane<T>* grad) {
  if (p.data.empty()) return T(0);
  const T inv = T(1) / T(p.data.size());
  T sum = 0;
  for (std::size_t i = 0; i < p.data.size(); ++i) {
    const T x = p.data[i];
    sum += std::abs(x);
    if (grad) grad->data[i] += scale * inv * T((x > T(0)) - (x < T(0)));
  }
  return sum * inv;
}

}  // namespace hdr4d::baselines::hexplane
