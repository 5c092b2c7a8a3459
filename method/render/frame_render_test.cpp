#include "method/render/frame_render.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <random>

#include "method/gaussian/constants.h"
#include "method/gaussian/sh4d.h"

namespace hdr4d::method {
namespace {

Camera TestCamera(int width = 24, int height = 20) {
  return Camera{PinholeIntrinsics::FromFovX(0.9, width, height),
                LookAtWorldFromCamGl({0.3, -4.0, 0.4}, {0, 0, 0}, Eigen::Vector3d::UnitZ())};
}

// A small random scene in front of TestCamera. Opacities stay moderate and colours positive so
// the finite differences meet few of the rasteriser's kinks (alpha thresholds, the LDR clamp).
template <typename T>
GaussianModelT<T> RandomScene(int n, bool temporal, unsigned seed) {
  std::mt19937 rng(seed);
  auto u = [&](double lo, double hi) {
    return static_cast<T>(std::uniform_real_distribution<double>(lo, hi)(rng));
  };
  GaussianModelT<T> m;
  m.temporal = temporal;
  if (!temporal) m.basis.max_time_degree = 0;
  m.channels = 3;
  m.Resize(n);
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) m.xyz[i * 3 + a] = u(-0.7, 0.7);
    m.t[i] = u(0.35, 0.65);
    for (int a = 0; a < 3; ++a) m.log_scales[i * 4 + a] = std::log(u(0.1, 0.3));
    m.log_scales[i * 4 + 3] = std::log(u(0.25, 0.5));
    for (int a = 0; a < 4; ++a) {
      m.rot_left[i * 4 + a] = u(-1, 1) + (a == 0 ? T(1.5) : T(0));
      m.rot_right[i * 4 + a] = u(-1, 1) + (a == 0 ? T(1.5) : T(0));
    }
    m.opacity_logit[i] = u(-1.5, 0.3);
    const std::size_t stride = m.rest_stride();
    for (std::size_t k = 0; k < stride; ++k) m.color_rest[i * stride + k] = u(-0.08, 0.08);
    for (int c = 0; c < 3; ++c) m.color_dc[i * 3 + c] = u(0.5, 1.5);  // positive colour
  }
  return m;
}

RenderOptions Options(bool temporal) {
  RenderOptions o;
  o.sh_degree = 3;
  o.time_degree = temporal ? 2 : 0;
  o.background = {0.1f, 0.2f, 0.3f};
  return o;
}

// L = sum(w * image) for fixed random weights w.
double WeightedSum(const std::vector<double>& image, const std::vector<double>& w) {
  double s = 0;
  for (std::size_t i = 0; i < image.size(); ++i) s += image[i] * w[i];
  return s;
}

// The reference detaches the colour's view direction and dt = mu_t - t, so the analytic
// gradient of the mean leaves out their (small) effect on colour. Geometry is therefore checked
// with degree-0 colour (no direction or time dependence), and the colour coefficients and
// opacity with the full basis.
void CheckWholeRenderGradient(bool temporal, unsigned seed, bool full_color_basis) {
  const Camera camera = TestCamera();
  GaussianModelT<double> model = RandomScene<double>(10, temporal, seed);
  RenderOptions options = Options(temporal);
  if (!full_color_basis) options.sh_degree = options.time_degree = 0;
  const double time = 0.5;
  const std::size_t pixels = 24 * 20 * 3;
  std::mt19937 rng(seed + 100);
  std::vector<double> w(pixels);
  for (double& x : w) x = std::uniform_real_distribution<double>(-1, 1)(rng);

  FrameStateT<double> state;
  std::vector<double> image(pixels);
  RenderForwardReference(model, camera, time, options, &state, image.data());
  ASSERT_GT(state.num_visible, 5u);
  GaussianGradientsT<double> grads;
  grads.ZerosLike(model);
  RenderBackwardReference(model, camera, time, options, &state, w.data(), &grads);

  auto loss = [&]() {
    FrameStateT<double> s;
    std::vector<double> img(pixels);
    RenderForwardReference(model, camera, time, options, &s, img.data());
    return WeightedSum(img, w);
  };
  const double h = 1e-6;
  int checked = 0, mismatched = 0, nonzero = 0;
  double max_abs = 0;
  auto check_field = [&](std::vector<double>& param, const std::vector<double>& grad,
                         const char* name, int width, int used) {
    for (std::size_t i = 0; i < param.size(); ++i) {
      if (static_cast<int>(i % width) >= used) continue;  // components the mode ignores
      const double saved = param[i];
      param[i] = saved + h;
      const double plus = loss();
      param[i] = saved - h;
      const double minus = loss();
      param[i] = saved;
      const double fd = (plus - minus) / (2 * h);
      const double an = grad[i];
      max_abs = std::max(max_abs, std::abs(an));
      if (std::abs(an) > 1e-8) ++nonzero;
      ++checked;
      if (std::abs(fd - an) > 2e-5 + 2e-4 * std::max(std::abs(fd), std::abs(an))) {
        ++mismatched;
        ADD_FAILURE() << name << "[" << i << "]: finite difference " << fd << ", analytic " << an;
      }
    }
  };
  if (!full_color_basis) {
    check_field(model.xyz, grads.xyz, "xyz", 3, 3);
    if (temporal) check_field(model.t, grads.t, "t", 1, 1);
    check_field(model.log_scales, grads.log_scales, "log_scales", 4, temporal ? 4 : 3);
    check_field(model.rot_left, grads.rot_left, "rot_left", 4, 4);
    if (temporal) check_field(model.rot_right, grads.rot_right, "rot_right", 4, 4);
  }
  check_field(model.opacity_logit, grads.opacity_logit, "opacity_logit", 1, 1);
  check_field(model.color_dc, grads.color_dc, "color_dc", 1, 1);
  // With degree-0 colour the other coefficients are inactive and get no gradient.
  if (full_color_basis) check_field(model.color_rest, grads.color_rest, "color_rest", 1, 1);
  EXPECT_EQ(mismatched, 0) << "of " << checked;
  EXPECT_GT(nonzero, checked / 3) << "the scene should exercise most parameters";
  EXPECT_GT(max_abs, 1e-3);
}

TEST(Render, WholeRenderGradientMatchesFiniteDifferences4D) {
  for (unsigned seed : {1u, 2u}) {
    CheckWholeRenderGradient(true, seed, false);
    CheckWholeRenderGradient(true, seed, true);
  }
}

TEST(Render, WholeRenderGradientMatchesFiniteDifferences3D) {
  CheckWholeRenderGradient(false, 3, false);
  CheckWholeRenderGradient(false, 3, true);
}

TEST(Render, FastPathMatchesTheReference) {
  const Camera camera = TestCamera(53, 41);
  const GaussianModel model = RandomScene<float>(200, true, 7);
  RenderOptions options = Options(true);
  FrameState fast_state, ref_state;
  std::vector<float> fast(53 * 41 * 3), ref(53 * 41 * 3);
  RenderForward(model, camera, 0.5f, options, &fast_state, fast.data());
  RenderForwardReference(model, camera, 0.5f, options, &ref_state, ref.data());
  for (std::size_t i = 0; i < fast.size(); ++i) ASSERT_NEAR(fast[i], ref[i], 2e-5) << i;

  std::vector<float> dL(fast.size());
  std::mt19937 rng(1);
  for (float& x : dL) x = std::uniform_real_distribution<float>(-1, 1)(rng);
  GaussianGradients g_fast, g_ref;
  g_fast.ZerosLike(model);
  g_ref.ZerosLike(model);
  RenderBackward(model, camera, 0.5f, options, &fast_state, dL.data(), &g_fast);
  RenderBackwardReference(model, camera, 0.5f, options, &ref_state, dL.data(), &g_ref);
  auto expect_close = [](const std::vector<float>& a, const std::vector<float>& b,
                         const char* name) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_NEAR(a[i], b[i], 1e-3 + 1e-3 * std::abs(b[i])) << name << "[" << i << "]";
    }
  };
  expect_close(g_fast.xyz, g_ref.xyz, "xyz");
  expect_close(g_fast.t, g_ref.t, "t");
  expect_close(g_fast.log_scales, g_ref.log_scales, "log_scales");
  expect_close(g_fast.opacity_logit, g_ref.opacity_logit, "opacity_logit");
  expect_close(g_fast.color_dc, g_ref.color_dc, "color_dc");
  expect_close(g_fast.color_rest, g_ref.color_rest, "color_rest");
}

// Colour bands left frozen (zero) by --color-bands-by-need: a render at the degrees the model
// uses (UsedColorDegrees) is the render at the full degrees, in 4D and 3D, up to float rounding
// (the SIMD colour kernel groups its sums by the degrees it evaluates).
TEST(Render, SkippingZeroColourBandsGivesTheSameImage) {
  const Camera camera = TestCamera(53, 41);
  for (bool temporal : {true, false}) {
    GaussianModel model = RandomScene<float>(200, temporal, 11);
    const std::size_t stride = model.rest_stride();
    // SH degree 1 on, everything above it zero.
    for (std::size_t i = 0; i < model.size(); ++i)
      std::fill(model.color_rest.begin() + i * stride + 9, model.color_rest.begin() + (i + 1) * stride,
                0.0f);
    ASSERT_EQ(UsedColorDegrees(model), (std::pair{1, 0}));
    RenderOptions full = Options(temporal), used = full;
    used.sh_degree = 1;
    used.time_degree = 0;
    FrameState a, b;
    std::vector<float> image_full(53 * 41 * 3), image_used(53 * 41 * 3);
    RenderForward(model, camera, 0.5f, full, &a, image_full.data());
    RenderForward(model, camera, 0.5f, used, &b, image_used.data());
    float worst = 0;
    for (std::size_t i = 0; i < image_full.size(); ++i)
      worst = std::max(worst, std::abs(image_full[i] - image_used[i]));
    EXPECT_LE(worst, 2e-6f) << (temporal ? "4D" : "3D");
  }
  GaussianModel model = RandomScene<float>(20, true, 3);
  EXPECT_EQ(UsedColorDegrees(model), (std::pair{3, 2}));
  std::fill(model.color_rest.begin(), model.color_rest.end(), 0.0f);
  EXPECT_EQ(UsedColorDegrees(model), (std::pair{0, 0}));
  model.color_rest[model.rest_stride() * 4 + 15 * 3] = 0.5f;  // k = 16: time block 1, l = 0
  EXPECT_EQ(UsedColorDegrees(model), (std::pair{0, 1}));
  model.color_rest[model.rest_stride() * 2 + 16 * 3 + 2] = 0.5f;  // k = 17: time block 1, l = 1
  EXPECT_EQ(UsedColorDegrees(model), (std::pair{1, 1}));
}

// rows_done hands over every Gaussian once, after its gradient rows are final (what the fused
// Adam step relies on): copies taken inside the callback (the colour rows from the callback's
// block, the others from grads) equal the gradients of a backward without the callback. The 4D
// model takes the SIMD preprocess, the 3D one the generic per-Gaussian code.
TEST(Render, RowsDoneSeesEachGaussianOnceWithFinalGradients) {
  for (const bool temporal : {true, false}) {
    const Camera camera = TestCamera(64, 48);
    const GaussianModel model = RandomScene<float>(3000, temporal, 11);
    const RenderOptions options = Options(temporal);
    FrameState state;
    std::vector<float> image(64 * 48 * 3), dL(image.size(), 0.01f);
    RenderForward(model, camera, 0.5f, options, &state, image.data());
    GaussianGradients plain, grads, seen;
    plain.ZerosLike(model);
    grads.ZerosLike(model);
    seen.ZerosLike(model);
    RenderBackward(model, camera, 0.5f, options, &state, dL.data(), &plain);
    std::vector<std::atomic<int>> calls(model.size());
    const std::size_t stride = model.rest_stride();
    RenderBackward(model, camera, 0.5f, options, &state, dL.data(), &grads,
                   [&](std::int64_t b, std::int64_t e, const GradientRows& colour) {
                     for (std::int64_t i = b; i < e; ++i) {
                       calls[i].fetch_add(1);
                       std::copy_n(&grads.xyz[i * 3], 3, &seen.xyz[i * 3]);
                       seen.opacity_logit[i] = grads.opacity_logit[i];
                       std::copy_n(colour.color_dc + (i - b) * 3, 3, &seen.color_dc[i * 3]);
                       std::copy_n(colour.color_rest + (i - b) * stride, stride,
                                   &seen.color_rest[i * stride]);
                     }
                   });
    for (std::size_t i = 0; i < model.size(); ++i) ASSERT_EQ(calls[i].load(), 1) << i;
    EXPECT_TRUE(seen.xyz == plain.xyz) << temporal;
    EXPECT_TRUE(seen.opacity_logit == plain.opacity_logit) << temporal;
    EXPECT_TRUE(seen.color_dc == plain.color_dc) << temporal;
    EXPECT_TRUE(seen.color_rest == plain.color_rest) << temporal;
    EXPECT_TRUE(std::any_of(plain.color_rest.begin(), plain.color_rest.end(),
                            [](float g) { return g != 0; }));
  }
}

TEST(Render, TemporallyDistantGaussiansAreCulled) {
  GaussianModel model = RandomScene<float>(3, true, 9);
  // Gaussian 1 lives at t = 0.5 with a short temporal extent: invisible at t = 0.
  model.t[1] = 0.5f;
  model.log_scales[1 * 4 + 3] = std::log(0.05f);
  model.rot_left.assign(12, 0.0f);
  model.rot_right.assign(12, 0.0f);
  for (int i = 0; i < 3; ++i)
    model.rot_left[i * 4] = model.rot_right[i * 4] = 1.0f;  // no space-time mixing
  FrameState state;
  PreprocessForward(model, ViewParams<float>::FromCamera(TestCamera()), 0.0f, Options(true),
                    &state);
  EXPECT_EQ(state.splats.radius[1], 0);
  PreprocessForward(model, ViewParams<float>::FromCamera(TestCamera()), 0.5f, Options(true),
                    &state);
  EXPECT_GT(state.splats.radius[1], 0);
  // The marginal multiplies the opacity: at its own time the Gaussian has its full opacity.
  EXPECT_NEAR(state.splats.opacity[1], 1 / (1 + std::exp(-model.opacity_logit[1])), 1e-6);
}

TEST(Render, LdrColourIsClampedAtZeroWithoutGradient) {
  GaussianModel model = RandomScene<float>(1, false, 4);
  model.xyz = {0, 0, 0};
  model.color_rest.assign(model.rest_stride(), 0.0f);
  model.color_dc = {-10.0f, 1.0f, 0.0f};  // red far below zero
  FrameState state;
  const Camera camera = TestCamera();
  std::vector<float> image(24 * 20 * 3);
  RenderOptions options = Options(false);
  options.background = {0, 0, 0};
  RenderForward(model, camera, 0.0f, options, &state, image.data());
  EXPECT_EQ(state.splats.features[0], 0.0f);
  EXPECT_GT(state.splats.features[1], 0.5f);
  std::vector<float> dL(image.size(), 1.0f);
  GaussianGradients grads;
  grads.ZerosLike(model);
  RenderBackward(model, camera, 0.0f, options, &state, dL.data(), &grads);
  EXPECT_EQ(grads.color_dc[0], 0.0f);
  EXPECT_GT(grads.color_dc[1], 0.0f);
}

// The preprocess alone (slice, cull, project, opacity x marginal, colour): a loss on every
// splat buffer, gradients to every model parameter against central differences in double.
// Degree-0 colour for the geometry (the view direction and dt are detached by design).
TEST(Render, PreprocessBackwardMatchesFiniteDifferences) {
  for (bool temporal : {true, false}) {
    GaussianModelT<double> model = RandomScene<double>(6, temporal, 31);
    RenderOptions options = Options(temporal);
    options.sh_degree = options.time_degree = 0;
    const ViewParams<double> view = ViewParams<double>::FromCamera(TestCamera());
    const double time = 0.5;
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    FrameStateT<double> state;
    PreprocessForward(model, view, time, options, &state);
    ASSERT_GT(state.num_visible, 3u);
    // Random weights on every splat value; the loss is their weighted sum.
    SplatBuffersT<double> w = state.splats;
    for (auto* v : {&w.mean2d, &w.conic, &w.opacity, &w.features})
      for (double& x : *v) x = u(rng);
    auto loss = [&](const GaussianModelT<double>& m) {
      FrameStateT<double> s;
      PreprocessForward(m, view, time, options, &s);
      double total = 0;
      for (std::size_t i = 0; i < m.size(); ++i) {
        if (s.splats.radius[i] != state.splats.radius[i]) ADD_FAILURE() << "visibility changed";
        if (s.splats.radius[i] <= 0) continue;
        for (int k = 0; k < 2; ++k) total += w.mean2d[2 * i + k] * s.splats.mean2d[2 * i + k];
        for (int k = 0; k < 3; ++k) total += w.conic[3 * i + k] * s.splats.conic[3 * i + k];
        total += w.opacity[i] * s.splats.opacity[i];
        for (int k = 0; k < 3; ++k) total += w.features[3 * i + k] * s.splats.features[3 * i + k];
      }
      return total;
    };
    state.splat_grads.SetZero(model.size(), 3);
    for (std::size_t i = 0; i < model.size(); ++i) {
      if (state.splats.radius[i] <= 0) continue;
      for (int k = 0; k < 2; ++k) state.splat_grads.mean2d[2 * i + k] = w.mean2d[2 * i + k];
      for (int k = 0; k < 3; ++k) state.splat_grads.conic[3 * i + k] = w.conic[3 * i + k];
      state.splat_grads.opacity[i] = w.opacity[i];
      for (int k = 0; k < 3; ++k) state.splat_grads.features[3 * i + k] = w.features[3 * i + k];
    }
    GaussianGradientsT<double> grads;
    grads.ZerosLike(model);
    PreprocessBackward(model, view, time, options, state, &grads);
    const double h = 1e-6;
    int checked = 0;
    for (auto [param, grad] :
         {std::pair{&model.xyz, &grads.xyz}, std::pair{&model.log_scales, &grads.log_scales},
          std::pair{&model.rot_left, &grads.rot_left},
          std::pair{&model.opacity_logit, &grads.opacity_logit},
          std::pair{&model.color_dc, &grads.color_dc}, std::pair{&model.t, &grads.t},
          std::pair{&model.rot_right, &grads.rot_right}}) {
      for (std::size_t i = 0; i < param->size(); ++i) {
        const double saved = (*param)[i];
        (*param)[i] = saved + h;
        const double plus = loss(model);
        (*param)[i] = saved - h;
        const double minus = loss(model);
        (*param)[i] = saved;
        const double fd = (plus - minus) / (2 * h);
        ASSERT_NEAR((*grad)[i], fd, 1e-5 + 1e-5 * std::abs(fd))
            << "temporal " << temporal << " entry " << i;
        ++checked;
      }
    }
    EXPECT_GT(checked, 100);
  }
}

}  // namespace
}  // namespace hdr4d::method
