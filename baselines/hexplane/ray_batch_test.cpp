#include "baselines/hexplane/ray_batch.h"

#include "core/util/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace hdr4d::baselines::hexplane {
namespace {

// Every part of the batch has its own double-precision finite-difference test (feature_plane,
// hex_field, app_mlp, volume_render). This checks their assembly, which runs in float: the
// directional derivative along a random direction of every parameter, against a central
// difference of float losses, so the tolerance is loose (a few percent) but a dropped or doubled
// term (a factor 2 or a sign) is far outside it.
HexPlaneModel SmallModel(ColorModel color, float shift) {
  HexPlaneConfig c;
  c.method = color == ColorModel::kLdr ? "hexplane" : "hdr-hexplane";
  c.color = color;
  c.voxels_init = 6 * 6 * 6;
  c.voxels_final = c.voxels_init;
  c.time_grid_init = c.time_grid_final = 3;
  c.density_comps = 2;
  c.app_comps = 3;
  c.app_dim = 4;
  c.mlp_hidden = 8;
  c.init_scale = 0.8f;
  c.init_shift = shift;  // a dense medium, so that densities and colours both matter
  c.density_shift = 0.0f;
  c.distance_scale = 1.0f;
  c.near = 1.0f;
  c.far = 4.0f;
  c.box = 1.0f;
  c.background = 0.3f;
  return HexPlaneModel::Create(c, 2);
}

std::vector<Ray> SomeRays() {
  std::vector<Ray> rays;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-0.4f, 0.4f);
  for (int i = 0; i < 40; ++i) {
    Ray r{{u(rng), u(rng), -2.5f}, {u(rng) * 0.3f, u(rng) * 0.3f, 1.0f}, u(rng) * 2, 0.2f, i % 2};
    const float n = std::sqrt(r.dir[0] * r.dir[0] + r.dir[1] * r.dir[1] + 1.0f);
    for (float& d : r.dir) d /= n;
    rays.push_back(r);
  }
  return rays;
}

// Every parameter of the model as pointers, in one fixed order.
std::vector<float*> Params(HexPlaneModel* m) {
  std::vector<float*> p;
  for (HexPlanes<float>* planes : {&m->density, &m->app})
    for (Plane<float>* q : planes->All())
      for (float& v : q->data) p.push_back(&v);
  for (auto* v : {&m->density_basis, &m->app_basis, &m->mlp, &m->exposure_offset})
    for (float& x : *v) p.push_back(&x);
  return p;
}
std::vector<float> Flat(HexPlaneGrads* g) {
  std::vector<float> out;
  for (HexPlanes<float>* planes : {&g->density, &g->app})
    for (Plane<float>* q : planes->All()) out.insert(out.end(), q->data.begin(), q->data.end());
  for (auto* v : {&g->density_basis, &g->app_basis, &g->mlp, &g->exposure_offset})
    out.insert(out.end(), v->begin(), v->end());
  return out;
}

double Loss(const HexPlaneModel& m, const std::vector<Ray>& rays, std::vector<float>* dout) {
  RayBatch batch;
  std::vector<float> out;
  batch.Forward(m, rays, nullptr, &out);
  double l = 0;
  if (dout) dout->resize(out.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double w = 0.5 + 0.1 * double(i % 7);
    l += w * out[i];
    if (dout) (*dout)[i] = float(w);
  }
  return l;
}

void CheckDirectionalDerivative(ColorModel color) {
  HexPlaneModel m = SmallModel(color, 0.9f);
  const std::vector<Ray> rays = SomeRays();
  std::vector<float> dout;
  Loss(m, rays, &dout);
  RayBatch batch;
  std::vector<float> out;
  batch.Forward(m, rays, nullptr, &out);
  ASSERT_GT(batch.app_samples(), 50);
  HexPlaneGrads g(m);
  batch.Backward(m, dout, &g);
  const std::vector<float> grad = Flat(&g);
  std::vector<float*> params = Params(&m);
  ASSERT_EQ(grad.size(), params.size());
  std::mt19937 rng(9);
  std::normal_distribution<float> n;
  std::vector<float> dir(params.size()), orig(params.size());
  double analytic = 0;
  for (std::size_t i = 0; i < params.size(); ++i) {
    dir[i] = n(rng);
    orig[i] = *params[i];
    analytic += double(dir[i]) * grad[i];
  }
  const float h = 2e-3f;
  auto at = [&](float s) {
    for (std::size_t i = 0; i < params.size(); ++i) *params[i] = orig[i] + s * dir[i];
    return Loss(m, rays, nullptr);
  };
  const double numeric = (at(h) - at(-h)) / (2 * h);
  EXPECT_NEAR(analytic, numeric, 0.03 * std::abs(numeric)) << "analytic " << analytic;
  EXPECT_GT(std::abs(numeric), 1.0);
}

TEST(RayBatch, LdrModelGradientMatchesAFiniteDifference) {
  CheckDirectionalDerivative(ColorModel::kLdr);
}
TEST(RayBatch, LogHdrModelGradientMatchesAFiniteDifference) {
  CheckDirectionalDerivative(ColorModel::kLogHdr);
}

TEST(RayBatch, EmptyModelShowsTheBackground) {
  HexPlaneModel m = SmallModel(ColorModel::kLdr, 0.0f);
  m.config.density_shift = -60.0f;  // softplus(-60): nothing in the box
  std::vector<float> out;
  RayBatch batch;
  batch.Forward(m, SomeRays(), nullptr, &out);
  for (float v : out) EXPECT_NEAR(v, 0.3f, 1e-6f);
  EXPECT_EQ(batch.app_samples(), 0);
}

// A view's other brackets through Reexpose are Forward's images at those exposures, bit for bit,
// for both colour models and with a learned (exposure-dependent) background.
TEST(RayBatch, ReexposeEqualsAForwardAtTheOtherExposure) {
  for (ColorModel color : {ColorModel::kLdr, ColorModel::kLogHdr})
    for (bool learned_background : {false, true}) {
      HexPlaneModel m = SmallModel(color, 0.5f);
      if (learned_background) {
        m.background.resize(9 * 3);
        for (std::size_t i = 0; i < m.background.size(); ++i)
          m.background[i] = 0.1f * float(i % 7) - 0.3f;
      }
      std::vector<Ray> rays = SomeRays();
      RayBatch batch;
      std::vector<float> first, again, direct;
      batch.Forward(m, rays, nullptr, &first);
      for (Ray& r : rays) r.log_exposure = -2.5f;
      batch.Reexpose(m, rays, &again);
      RayBatch fresh;
      fresh.Forward(m, rays, nullptr, &direct);
      ASSERT_EQ(again.size(), direct.size());
      for (std::size_t i = 0; i < direct.size(); ++i)
        ASSERT_EQ(again[i], direct[i]) << "value " << i << " learned " << learned_background;
      // The LDR model has no exposure input; the log-HDR one's LDR channels change with it.
      EXPECT_EQ(first == again, color == ColorModel::kLdr);
      rays.pop_back();
      EXPECT_THROW(batch.Reexpose(m, rays, &again), Error);
    }
}

}  // namespace
}  // namespace hdr4d::baselines::hexplane
