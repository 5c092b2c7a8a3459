// The occupancy grid of HexPlaneModel (the reference's emptiness volume, after TensoRF's alpha
// mask): the largest opacity a point reaches over time, dilated by a 3 x 3 x 3 max filter and
// thresholded.
#include <algorithm>
#include <cmath>

#include "baselines/hexplane/hexplane_model.h"
#include "baselines/hexplane/volume_render.h"
#include "core/util/parallel.h"

namespace hdr4d::baselines::hexplane {
namespace {

// max over `times` time samples in [-1, 1] of the density feature at xyz. The spatial lookups
// do not depend on time, so they are made once.
float MaxDensityFeature(const HexPlaneModel& m, const float xyz[3], int times,
                        std::vector<float>* scratch) {
  const int n = m.config.density_comps;
  scratch->resize(4 * n);
  float* s = scratch->data();  // 3 x n: S_i * b_i
  float* l = s + 3 * n;
  for (int i = 0; i < 3; ++i) {
    const auto tap =
        MakeTap(m.density.space[i], xyz[kPlaneAxes[i][0]], xyz[kPlaneAxes[i][1]]);
    Gather(m.density.space[i], tap, s + i * n);
    for (int c = 0; c < n; ++c) s[i * n + c] *= m.density_basis[i * n + c];
  }
  float best = -INFINITY;
  for (int k = 0; k < times; ++k) {
    const float t = times > 1 ? -1.0f + 2.0f * k / (times - 1) : 0.0f;
    float f = 0;
    for (int i = 0; i < 3; ++i) {
      Gather(m.density.time[i], MakeTap(m.density.time[i], t, xyz[kLineAxis[i]]), l);
      for (int c = 0; c < n; ++c) f += s[i * n + c] * l[c];
    }
    best = std::max(best, f);
  }
  return best;
}

// The 3 x 3 x 3 max filter (zero beyond the border, as max_pool3d's padding never wins over
// non-negative values).
std::vector<float> MaxPool3(const std::vector<float>& v, const std::array<int, 3>& r) {
  std::vector<float> out(v.size(), 0.0f);
  ParallelFor(r[2], 1, [&](std::int64_t z) {
    for (int y = 0; y < r[1]; ++y)
      for (int x = 0; x < r[0]; ++x) {
        float best = 0;
        for (int dz = -1; dz <= 1; ++dz)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const int zz = int(z) + dz, yy = y + dy, xx = x + dx;
              if (zz < 0 || yy < 0 || xx < 0 || zz >= r[2] || yy >= r[1] || xx >= r[0]) continue;
              best = std::max(best, v[(std::size_t(zz) * r[1] + yy) * r[0] + xx]);
            }
        out[(std::size_t(z) * r[1] + y) * r[0] + x] = best;
      }
  });
  return out;
}

}  // namespace

bool HexPlaneModel::UpdateOccupancy() {
  std::array<int, 3> r;
  for (int a = 0; a < 3; ++a) r[a] = std::min(grid[a], 256);  // the reference's 256^3 cap
  std::vector<float> opacity(std::size_t(r[0]) * r[1] * r[2], 0.0f);
  const float step = StepSize();
  ParallelFor(r[2], 1, [&](std::int64_t z) {
    std::vector<float> scratch;
    for (int y = 0; y < r[1]; ++y)
      for (int x = 0; x < r[0]; ++x) {
        const float xyz[3] = {-1.0f + 2.0f * x / (r[0] - 1), -1.0f + 2.0f * y / (r[1] - 1),
                              -1.0f + 2.0f * float(z) / (r[2] - 1)};
        if (!occupancy.Keeps(xyz)) continue;  // empty before: stays empty
        const float f = MaxDensityFeature(*this, xyz, config.occupancy_time_samples, &scratch);
        const float sigma = Softplus(f + config.density_shift);
        opacity[(std::size_t(z) * r[1] + y) * r[0] + x] = -std::expm1(-sigma * step);
      }
  });
  const std::vector<float> pooled = MaxPool3(opacity, r);
  // A grid with nothing occupied would end training (empty stays empty): a schedule scaled
  // into a short run can come before any density has formed; such an update is skipped.
  if (std::none_of(pooled.begin(), pooled.end(),
                   [&](float v) { return v >= config.occupancy_threshold; }))
    return false;
  OccupancyGrid g;
  g.res = r;
  g.occupied.resize(pooled.size());
  for (std::size_t i = 0; i < pooled.size(); ++i)
    g.occupied[i] = pooled[i] >= config.occupancy_threshold ? 1 : 0;
  occupancy = std::move(g);
  return true;
}

}  // namespace hdr4d::baselines::hexplane
