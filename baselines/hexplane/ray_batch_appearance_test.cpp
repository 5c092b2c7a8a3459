// RayBatch::Lane::AppearanceBackward (ray_batch_appearance.cpp), the backward of the appearance
// half of a ray batch: planes -> basis matrix -> MLP -> colour (LDR sigmoid, or log radiance with
// HDR = exp and LDR = sigmoid(ln radiance + ln exposure + offset)). It alone writes the gradients
// of the appearance planes, the appearance basis, the MLP and the exposure offsets (with the
// learned background of background_env.h beside it, whose coefficients are checked too), so these
// are checked here, through RayBatch::Backward with the density path held fixed (only appearance
// parameters move, so the samples, their weights and the set that gets a colour stay the same).
//
// The model and the batch are float only (HexPlaneModel holds float parameters; its parts have
// double-precision tests of their own: feature_plane, hex_field, app_mlp, volume_render), so the
// forward cannot run in double here. The differences are taken on the float forward with the
// loss summed in double, one random direction per parameter group, with the MLP's hidden units
// all on (below) so that the loss is smooth: with a step of 3e-3 the differences agree with the
// analytic derivative to 0.2% (measured: smaller steps drown in float rounding, larger ones in
// curvature), under the 1% tolerance, and a sign slip or a dropped term in any group is far
// outside it.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "baselines/hexplane/hexplane_model.h"
#include "baselines/hexplane/ray_batch.h"

namespace hdr4d::baselines::hexplane {
namespace {

HexPlaneModel Model(ColorModel color, const std::string& background_model = "fixed") {
  HexPlaneConfig c;
  c.background_model = background_model;
  c.method = color == ColorModel::kLdr ? "hexplane" : "hdr-hexplane";
  c.color = color;
  c.voxels_init = c.voxels_final = 6 * 6 * 6;
  c.time_grid_init = c.time_grid_final = 3;
  c.density_comps = 2;
  c.app_comps = 3;
  c.app_dim = 4;
  c.mlp_hidden = 8;
  c.init_scale = 0.8f;
  c.init_shift = 0.9f;  // a dense medium: many samples get a colour
  c.density_shift = 0.0f;
  // With a learned background, a thinner medium so that the sky shows behind it (a ray keeps
  // a fair share of its transmittance to the end, and the background's gradient is far above
  // float noise).
  c.distance_scale = background_model == "fixed" ? 1.0f : 0.1f;
  c.near = 1.0f;
  c.far = 4.0f;
  c.box = 1.0f;
  c.background = 0.3f;
  HexPlaneModel m = HexPlaneModel::Create(c, 2);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  for (float& v : m.exposure_offset) v = u(rng);  // distinct offsets per image
  for (float& v : m.background) v += u(rng);      // a sky that varies with the direction
  for (float& v : m.app_basis) v *= 3.0f;         // the planes' share of the colour grows
  // Every hidden unit on: the first layer's weights shrunk and its biases raised, the second's
  // made non-negative. The loss is then smooth (no ReLU kink within a step), which float
  // differences need to converge; the ReLU's own backward is app_mlp's (app_mlp_test.cpp).
  const std::vector<int>& w = m.MlpShape().Layers().widths;
  std::size_t at = 0;
  for (std::size_t l = 0; l + 2 < w.size(); ++l) {
    const std::size_t weights = std::size_t(w[l]) * w[l + 1];
    for (std::size_t k = at; k < at + weights; ++k)
      m.mlp[k] = l == 0 ? 0.25f * m.mlp[k] : std::abs(m.mlp[k]);
    for (std::size_t k = at + weights; k < at + weights + w[l + 1]; ++k)
      m.mlp[k] = l == 0 ? m.mlp[k] + 2.0f : std::abs(m.mlp[k]) + 0.5f;
    at += weights + w[l + 1];
  }
  return m;
}

std::vector<Ray> Rays() {
  std::vector<Ray> rays;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.4f, 0.4f);
  for (int i = 0; i < 30; ++i) {
    Ray r{{u(rng), u(rng), -2.5f}, {u(rng) * 0.3f, u(rng) * 0.3f, 1.0f}, u(rng) * 2, 0.2f, i % 2};
    const float n = std::sqrt(r.dir[0] * r.dir[0] + r.dir[1] * r.dir[1] + 1.0f);
    for (float& d : r.dir) d /= n;
    rays.push_back(r);
  }
  return rays;
}

// The appearance parameter groups of a model (or of its gradients): name and values.
struct Group {
  std::string name;
  std::vector<float*> values;
};
template <typename Model>
std::vector<Group> AppearanceGroups(Model* m) {
  std::vector<Group> groups(5);
  groups[0].name = "app planes";
  for (auto* plane : m->app.All())
    for (float& v : plane->data) groups[0].values.push_back(&v);
  const std::pair<const char*, std::vector<float>*> flat[] = {
      {"app basis", &m->app_basis},
      {"mlp", &m->mlp},
      {"exposure offsets", &m->exposure_offset},
      {"background", &m->background}};
  for (int k = 0; k < 4; ++k) {
    groups[1 + k].name = flat[k].first;
    for (float& v : *flat[k].second) groups[1 + k].values.push_back(&v);
  }
  return groups;
}

// sum_i w_i out_i in double, w_i fixed per output.
double Loss(const HexPlaneModel& m, const std::vector<Ray>& rays, std::vector<float>* weights) {
  RayBatch batch;
  std::vector<float> out;
  batch.Forward(m, rays, nullptr, &out);
  if (weights) {
    weights->resize(out.size());
    for (std::size_t i = 0; i < out.size(); ++i) (*weights)[i] = float(0.5 + 0.1 * double(i % 7));
  }
  double l = 0;
  for (std::size_t i = 0; i < out.size(); ++i) l += (0.5 + 0.1 * double(i % 7)) * out[i];
  return l;
}

void CheckAppearanceBackward(ColorModel color, const std::string& background_model = "fixed") {
  HexPlaneModel m = Model(color, background_model);
  const std::vector<Ray> rays = Rays();
  std::vector<float> weights;
  Loss(m, rays, &weights);
  RayBatch batch;
  std::vector<float> out;
  batch.Forward(m, rays, nullptr, &out);
  ASSERT_GT(batch.app_samples(), 50);
  HexPlaneGrads g(m);
  batch.Backward(m, weights, &g);
  std::vector<Group> params = AppearanceGroups(&m);
  const std::vector<Group> grads = AppearanceGroups(&g);
  std::mt19937 rng(11);
  std::normal_distribution<float> normal;
  for (std::size_t k = 0; k < params.size(); ++k) {
    SCOPED_TRACE(params[k].name);
    const std::vector<float*>& p = params[k].values;
    ASSERT_EQ(p.size(), grads[k].values.size());
    if (color == ColorModel::kLdr && params[k].name == "exposure offsets") {
      for (const float* v : grads[k].values) EXPECT_EQ(*v, 0.0f);  // unused by LDR colours
      continue;
    }
    if (p.empty()) continue;  // no learned background
    std::vector<float> dir(p.size()), orig(p.size());
    double analytic = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      dir[i] = normal(rng);
      orig[i] = *p[i];
      analytic += double(dir[i]) * double(*grads[k].values[i]);
    }
    const float h = 3e-3f;
    const auto at = [&](float s) {
      for (std::size_t i = 0; i < p.size(); ++i) *p[i] = orig[i] + s * dir[i];
      const double l = Loss(m, rays, nullptr);
      for (std::size_t i = 0; i < p.size(); ++i) *p[i] = orig[i];
      return l;
    };
    const double numeric = (at(h) - at(-h)) / (2.0 * double(h));
    EXPECT_NEAR(analytic, numeric, 0.01 * std::abs(numeric)) << "analytic " << analytic;
    EXPECT_GT(std::abs(numeric), 0.02);  // far above the float noise (~1e-4): the check can fail
  }
}

TEST(RayBatchAppearance, AppearanceBackwardMatchesFiniteDifferencesLdr) {
  CheckAppearanceBackward(ColorModel::kLdr);
}
TEST(RayBatchAppearance, AppearanceBackwardMatchesFiniteDifferencesLogHdr) {
  CheckAppearanceBackward(ColorModel::kLogHdr);
}
// With a learned environment behind the box (background_env.h): its coefficients, and the
// exposure offsets that now also reach the sky.
TEST(RayBatchAppearance, BackwardMatchesFiniteDifferencesWithAnEnvironmentLdr) {
  CheckAppearanceBackward(ColorModel::kLdr, "environment");
}
TEST(RayBatchAppearance, BackwardMatchesFiniteDifferencesWithAnEnvironmentLogHdr) {
  CheckAppearanceBackward(ColorModel::kLogHdr, "environment");
}

}  // namespace
}  // namespace hdr4d::baselines::hexplane
