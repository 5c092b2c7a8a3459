// HexPlane's field (Cao & Johnson 2023, the reference's HexPlane_Slim): for density and for
// appearance, three spatial planes (XY, XZ, YZ) and three space-time planes (ZT, YT, XT), spatial
// plane i paired with the space-time plane of the remaining axis. At a point (x, y, z, t), all in
// [-1, 1], pair i gives the product S_i * L_i of the two lookups per component ("multiply"
// fusion). Density: sum_i sum_c S_i[c] L_i[c] b_i[c] with a learned basis b (initialised to
// ones). Appearance: the 3 x n products concatenated ("concat" fusion), then a basis matrix
// (app_dim x 3n, no bias) to the appearance MLP's feature.
#pragma once

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "baselines/hexplane/feature_plane.h"

namespace hdr4d::baselines::hexplane {

// Spatial plane i reads axes kPlaneAxes[i] (width, height); its space-time partner reads
// kLineAxis[i] along the height and time along the width (the reference's matMode, vecMode).
inline constexpr int kPlaneAxes[3][2] = {{0, 1}, {0, 2}, {1, 2}};
inline constexpr int kLineAxis[3] = {2, 1, 0};

template <typename T>
struct HexPlanes {
  std::array<Plane<T>, 3> space, time;

  HexPlanes() = default;
  // grid: x, y, z resolutions; time_grid: the space-time planes' width.
  HexPlanes(int comps, const std::array<int, 3>& grid, int time_grid) {
    for (int i = 0; i < 3; ++i) {
      space[i] = Plane<T>(comps, grid[kPlaneAxes[i][1]], grid[kPlaneAxes[i][0]]);
      time[i] = Plane<T>(comps, grid[kLineAxis[i]], time_grid);
    }
  }
  int comps() const { return space[0].comps; }
  // Every plane in a fixed order (space 0-2, time 0-2): optimiser and checkpoint walk it.
  std::array<Plane<T>*, 6> All() {
    return {&space[0], &space[1], &space[2], &time[0], &time[1], &time[2]};
  }
  std::array<const Plane<T>*, 6> All() const {
    return {&space[0], &space[1], &space[2], &time[0], &time[1], &time[2]};
  }
  void SetZero() {
    for (Plane<T>* p : All()) std::fill(p->data.begin(), p->data.end(), T(0));
  }
};

// The six lookups of one point (spatial planes first). Density and appearance planes share a
// resolution, so one set of taps serves both.
template <typename T>
struct PointTaps {
  BilinearTap<T> space[3], time[3];
};

template <typename T>
PointTaps<T> MakePointTaps(const HexPlanes<T>& planes, const T xyz[3], T t) {
  PointTaps<T> taps;
  for (int i = 0; i < 3; ++i) {
    taps.space[i] = MakeTap(planes.space[i], xyz[kPlaneAxes[i][0]], xyz[kPlaneAxes[i][1]]);
    taps.time[i] = MakeTap(planes.time[i], t, xyz[kLineAxis[i]]);
  }
  return taps;
}

// The density feature (before softplus). scratch: 2 x comps.
template <typename T>
T DensityFeature(const HexPlanes<T>& planes, const std::vector<T>& basis, const PointTaps<T>& taps,
                 T* scratch) {
  const int n = planes.comps();
  T* s = scratch;
  T* l = scratch + n;
  T f = 0;
  for (int i = 0; i < 3; ++i) {
    Gather(planes.space[i], taps.space[i], s);
    Gather(planes.time[i], taps.time[i], l);
    const T* b = basis.data() + std::size_t(i) * n;
    for (int c = 0; c < n; ++c) f += s[c] * l[c] * b[c];
  }
  return f;
}

// Backward of DensityFeature: adds to the plane and basis gradients. scratch: 4 x comps.
template <typename T>
void DensityFeatureBackward(const HexPlanes<T>& planes, const std::vector<T>& basis,
                            const PointTaps<T>& taps, T dL_df, HexPlanes<T>* dplanes,
                            std::vector<T>* dbasis, T* scratch) {
  const int n = planes.comps();
  T *s = scratch, *l = scratch + n, *ds = scratch + 2 * n, *dl = scratch + 3 * n;
  for (int i = 0; i < 3; ++i) {
    Gather(planes.space[i], taps.space[i], s);
    Gather(planes.time[i], taps.time[i], l);
    const T* b = basis.data() + std::size_t(i) * n;
    T* db = dbasis->data() + std::size_t(i) * n;
    for (int c = 0; c < n; ++c) {
      ds[c] = dL_df * l[c] * b[c];
      dl[c] = dL_df * s[c] * b[c];
      db[c] += dL_df * s[c] * l[c];
    }
    Scatter(taps.space[i], ds, &dplanes->space[i]);
    Scatter(taps.time[i], dl, &dplanes->time[i]);
  }
}

// The appearance products S_i[c] L_i[c], concatenated over i: out has 3 x comps values (the
// basis matrix is applied to many points at once by the caller). scratch: comps.
template <typename T>
void AppProducts(const HexPlanes<T>& planes, const PointTaps<T>& taps, T* out, T* scratch) {
  const int n = planes.comps();
  for (int i = 0; i < 3; ++i) {
    T* p = out + std::size_t(i) * n;
    Gather(planes.space[i], taps.space[i], p);
    Gather(planes.time[i], taps.time[i], scratch);
    for (int c = 0; c < n; ++c) p[c] *= scratch[c];
  }
}

// Backward of AppProducts for dL_dout (3 x comps). scratch: 4 x comps.
template <typename T>
void AppProductsBackward(const HexPlanes<T>& planes, const PointTaps<T>& taps, const T* dL_dout,
                         HexPlanes<T>* dplanes, T* scratch) {
  const int n = planes.comps();
  T *s = scratch, *l = scratch + n, *ds = scratch + 2 * n, *dl = scratch + 3 * n;
  for (int i = 0; i < 3; ++i) {
    Gather(planes.space[i], taps.space[i], s);
    Gather(planes.time[i], taps.time[i], l);
    const T* g = dL_dout + std::size_t(i) * n;
    for (int c = 0; c < n; ++c) {
      ds[c] = g[c] * l[c];
      dl[c] = g[c] * s[c];
    }
    Scatter(taps.space[i], ds, &dplanes->space[i]);
    Scatter(taps.time[i], dl, &dplanes->time[i]);
  }
}

// The reference's initialisation: scale * N(0, 1) + shift for every plane value.
template <typename T>
void InitPlanes(T scale, T shift, std::uint64_t seed, HexPlanes<T>* planes) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (Plane<T>* p : planes->All())
    for (T& v : p->data) v = T(scale * normal(rng) + shift);
}

}  // namespace hdr4d::baselines::hexplane
