#include "baselines/hexplane/hexplane_model.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include "baselines/hexplane/background_env.h"
#include "baselines/hexplane/volume_render.h"
#include "core/files/atomic_file.h"
#include "core/util/error.h"
#include "core/util/parallel.h"

namespace hdr4d::baselines::hexplane {

bool OccupancyGrid::Keeps(const float xyz[3]) const {
  if (occupied.empty()) return true;
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    const float f = std::clamp((xyz[a] + 1.0f) * 0.5f * (res[a] - 1), 0.0f, float(res[a] - 1));
    lo[a] = std::min(static_cast<int>(f), res[a] - 2);
    hi[a] = f > float(lo[a]) ? lo[a] + 1 : lo[a];  // on a grid point only that point counts
  }
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int x = lo[0]; x <= hi[0]; ++x)
        if (occupied[(std::size_t(z) * res[1] + y) * res[0] + x]) return true;
  return false;
}

std::array<int, 3> ResolutionOf(std::int64_t voxels) {
  // A cube box: the cube root (rounded down, as the reference's .long(); the epsilon keeps
  // 64^3 at 64 against rounding).
  const int r = std::max(2, static_cast<int>(std::cbrt(double(voxels)) + 1e-6));
  return {r, r, r};
}

std::vector<std::int64_t> VoxelSchedule(const HexPlaneConfig& c) {
  const int n = static_cast<int>(c.upsample_at.size());
  std::vector<std::int64_t> out;
  for (int k = 1; k <= n; ++k) {
    const double a = std::log(double(c.voxels_init)), b = std::log(double(c.voxels_final));
    out.push_back(static_cast<std::int64_t>(std::llround(std::exp(a + (b - a) * k / n))));
  }
  return out;
}

std::vector<int> TimeGridSchedule(const HexPlaneConfig& c) {
  const int n = static_cast<int>(c.upsample_at.size());
  std::vector<int> out;
  for (int k = 1; k <= n; ++k) {
    const double a = std::log(double(c.time_grid_init)), b = std::log(double(c.time_grid_final));
    out.push_back(static_cast<int>(std::lround(std::exp(a + (b - a) * k / n))));
  }
  return out;
}

HexPlaneModel HexPlaneModel::Create(const HexPlaneConfig& config, int num_train_images) {
  HexPlaneModel m;
  m.config = config;
  m.grid = ResolutionOf(config.voxels_init);
  m.time_grid = config.time_grid_init;
  m.density = HexPlanes<float>(config.density_comps, m.grid, m.time_grid);
  m.app = HexPlanes<float>(config.app_comps, m.grid, m.time_grid);
  InitPlanes(config.init_scale, config.init_shift, config.seed, &m.density);
  InitPlanes(config.init_scale, config.init_shift, config.seed + 1, &m.app);
  m.density_basis.assign(3 * config.density_comps, 1.0f);
  // nn.Linear(3 n, app_dim, bias=False): uniform in +-1/sqrt(3 n).
  std::mt19937_64 rng(config.seed + 2);
  const double bound = 1.0 / std::sqrt(3.0 * config.app_comps);
  std::uniform_real_distribution<double> u(-bound, bound);
  m.app_basis.resize(std::size_t(config.app_dim) * 3 * config.app_comps);
  for (float& v : m.app_basis) v = float(u(rng));
  m.mlp = InitAppMlp(m.MlpShape(), config.seed + 3);
  if (config.color == ColorModel::kLogHdr) m.exposure_offset.assign(num_train_images, 0.0f);
  // A learned background starts uniform at the fixed one (kept off the sigmoid's flat ends; the
  // log-HDR model's at a radiance of at least 0.05).
  const int n = BackgroundBasisSize(config.background_model);
  if (n > 0) {
    const float b = std::clamp(config.background, 0.05f, 0.95f);
    const float pre = config.color == ColorModel::kLdr
                          ? std::log(b / (1.0f - b))
                          : std::log(std::max(config.background, 0.05f));
    const float up[3] = {0.0f, 0.0f, 1.0f};  // degree 0 is the same in every direction
    float y0;
    BackgroundBasis(up, 1, &y0);
    m.background.assign(std::size_t(n) * 3, 0.0f);
    for (int k = 0; k < 3; ++k) m.background[k] = pre / y0;
  }
  return m;
}

AppMlpShape HexPlaneModel::MlpShape() const {
  AppMlpShape s;
  s.feature = config.app_dim;
  s.fea_pe = config.fea_pe;
  s.view_pe = config.view_pe;
  s.hidden = config.mlp_hidden;
  s.sigmoid_output = config.color == ColorModel::kLdr;
  return s;
}

float HexPlaneModel::StepSize() const {
  double units = 0;
  for (int a = 0; a < 3; ++a) units += 2.0 * config.box / (grid[a] - 1);
  return float(units / 3 * config.step_ratio);
}

int HexPlaneModel::NumSamples() const {
  const double diagonal = std::sqrt(3.0) * 2.0 * config.box;
  return static_cast<int>(diagonal / StepSize()) + 1;
}

void HexPlaneModel::Upsample(const std::array<int, 3>& new_grid, int new_time_grid) {
  for (HexPlanes<float>* planes : {&density, &app}) {
    for (int i = 0; i < 3; ++i) {
      Plane<float>& s = planes->space[i];
      s = Resized(s, new_grid[kPlaneAxes[i][1]], new_grid[kPlaneAxes[i][0]]);
      Plane<float>& t = planes->time[i];
      t = Resized(t, new_grid[kLineAxis[i]], new_time_grid);
    }
  }
  grid = new_grid;
  time_grid = new_time_grid;
}

float HexPlaneModel::OffsetOf(int image_index) const {
  if (exposure_offset.empty()) return 0.0f;
  if (image_index >= 0 && image_index < int(exposure_offset.size()))
    return exposure_offset[image_index];
  double sum = 0;
  for (float o : exposure_offset) sum += o;
  return float(sum / exposure_offset.size());
}

HexPlaneGrads::HexPlaneGrads(const HexPlaneModel& m)
    : density(m.config.density_comps, m.grid, m.time_grid),
      app(m.config.app_comps, m.grid, m.time_grid),
      density_basis(m.density_basis.size(), 0.0f),
      app_basis(m.app_basis.size(), 0.0f),
      mlp(m.mlp.size(), 0.0f),
      exposure_offset(m.exposure_offset.size(), 0.0f),
      background(m.background.size(), 0.0f) {}

void HexPlaneGrads::SetZero() {
  density.SetZero();
  app.SetZero();
  for (auto* v : {&density_basis, &app_basis, &mlp, &exposure_offset, &background})
    std::fill(v->begin(), v->end(), 0.0f);
}

void HexPlaneGrads::Add(const HexPlaneGrads& o) {
  const auto add = [](std::vector<float>& a, const std::vector<float>& b) {
    for (std::size_t i = 0; i < a.size(); ++i) a[i] += b[i];
  };
  for (int k = 0; k < 6; ++k) {
    add(density.All()[k]->data, o.density.All()[k]->data);
    add(app.All()[k]->data, o.app.All()[k]->data);
  }
  add(density_basis, o.density_basis);
  add(app_basis, o.app_basis);
  add(mlp, o.mlp);
  add(exposure_offset, o.exposure_offset);
  add(background, o.background);
}

}  // namespace hdr4d::baselines::hexplane
