// The fast preprocess against the reference (preprocess.h), forward and backward, on every
// Highway target compiled in, on random scenes and on the edge cases where the two could part:
// the near plane, the frustum guard band, the time-variance floor, Gaussians culled in time,
// degenerate scales, one Gaussian and none.
#include "method/render/preprocess.h"

#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/geometry/camera.h"
#include "method/gaussian/sh4d.h"
#include "method/raster/simd_targets_for_test.h"
#include "method/render/preprocess_simd.h"
#include "tests/finite_difference.h"

namespace hdr4d::method {
namespace {

constexpr float kTime = 0.5f;

Camera TestCamera() {
  return Camera{PinholeIntrinsics::FromFovX(0.9, 64, 48),
                LookAtWorldFromCamGl({0.3, -4.0, 0.4}, {0, 0, 0}, Eigen::Vector3d::UnitZ())};
}

// Gaussian i with identity-ish rotations, the given centre, time and log-scales.
void SetGaussian(GaussianModel& m,
                 int i,
                 const Eigen::Vector3d& p,
                 float t,
                 float log_scale,
                 float log_time_scale,
                 std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int a = 0; a < 3; ++a) m.xyz[i * 3 + a] = static_cast<float>(p[a]);
  m.t[i] = t;
  for (int a = 0; a < 3; ++a) m.log_scales[i * 4 + a] = log_scale + 0.3f * u(rng);
  m.log_scales[i * 4 + 3] = log_time_scale;
  for (int a = 0; a < 4; ++a) {
    m.rot_left[i * 4 + a] = 0.4f * u(rng) + (a == 0 ? 1.0f : 0.0f);
    m.rot_right[i * 4 + a] = 0.4f * u(rng) + (a == 0 ? 1.0f : 0.0f);
  }
  m.opacity_logit[i] = 1.5f * u(rng);
  for (int c = 0; c < 3; ++c) m.color_dc[i * 3 + c] = 0.5f + 0.5f * u(rng);
  const std::size_t stride = m.rest_stride();
  for (std::size_t k = 0; k < stride; ++k) m.color_rest[i * stride + k] = 0.1f * u(rng);
}

// `random` Gaussians in front of the camera, then (with edge_cases) the ones on the boundaries.
GaussianModel Scene(int random, bool edge_cases, unsigned seed) {
  const Camera camera = TestCamera();
  const Eigen::Vector3d eye = camera.Center();
  const Eigen::Matrix3d world_from_cam = camera.world_from_cam_gl.topLeftCorner<3, 3>();
  // OpenGL camera axes: x right, y up, looking down -z.
  const Eigen::Vector3d right = world_from_cam.col(0), up = world_from_cam.col(1),
                        forward = -world_from_cam.col(2);
  const double tan_x = std::tan(0.45);  // half of the 0.9 rad horizontal field of view
  std::vector<Eigen::Vector3d> points;
  std::vector<std::pair<float, float>> scales;  // log spatial scale, log time scale
  std::vector<float> times;
  if (edge_cases) {
    for (double depth : {0.15, 0.199, 0.201, 0.25, 0.5}) {  // around kNearPlane = 0.2
      points.push_back(eye + depth * forward + 0.01 * right);
      scales.push_back({std::log(0.05f), std::log(0.3f)});
      times.push_back(kTime);
    }
    for (double side : {-1.0, 1.0}) {  // around the guard band at 1.3 tan(fov / 2)
      for (double f : {1.1, 1.29, 1.31, 1.6}) {
        points.push_back(eye + 3.0 * forward + side * f * tan_x * 3.0 * right);
        scales.push_back({std::log(0.2f), std::log(0.3f)});
        times.push_back(kTime);
      }
    }
    for (float log_time_scale : {std::log(1e-6f), std::log(1e-12f), -40.0f}) {  // floor
      points.push_back(eye + 4.0 * forward + 0.2 * up);
      scales.push_back({std::log(0.1f), log_time_scale});
      times.push_back(kTime);
    }
    for (float t : {kTime + 0.9f, kTime - 2.0f, kTime + 0.31f}) {  // culled in time, or nearly
      points.push_back(eye + 4.0 * forward);
      scales.push_back({std::log(0.1f), std::log(0.12f)});
      times.push_back(t);
    }
    for (float log_scale : {-16.0f, -9.0f, 2.0f}) {  // needle, dot and a huge Gaussian
      points.push_back(eye + 4.0 * forward - 0.3 * right);
      scales.push_back({log_scale, std::log(0.3f)});
      times.push_back(kTime);
    }
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < random; ++i) {
    points.push_back(Eigen::Vector3d(0.8 * u(rng), 0.8 * u(rng), 0.8 * u(rng)));
    scales.push_back({static_cast<float>(std::log(0.1) + 0.5 * u(rng)),
                      static_cast<float>(std::log(0.3) + 0.3 * u(rng))});
    times.push_back(static_cast<float>(0.5 + 0.2 * u(rng)));
  }
  GaussianModel m;
  m.temporal = true;
  m.channels = 3;
  m.Resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    SetGaussian(m, static_cast<int>(i), points[i], times[i], scales[i].first, scales[i].second,
                rng);
  }
  return m;
}

// |a - b| within abs + rel * |b| for every value; returns how many were not.
int CountFar(const std::vector<float>& a,
             const std::vector<float>& b,
             float abs,
             float rel,
             const std::string& name) {
  EXPECT_EQ(a.size(), b.size()) << name;
  int far = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    if (!(std::abs(a[i] - b[i]) <= abs + rel * std::abs(b[i]))) {
      if (far < 5)
        ADD_FAILURE() << name << "[" << i << "]: fast " << a[i] << ", reference " << b[i];
      ++far;
    }
  }
  return far;
}

// Options with the given SH degree and the time degree 2 (every colour block in use).
RenderOptions ColourOptions(int sh_degree) {
  RenderOptions options;
  options.sh_degree = sh_degree;
  options.time_degree = 2;
  return options;
}

// Random splat gradients in [-1, 1) for the Gaussians visible in both radii (a state's own radii
// twice for one state), zero for the others; the draws in Gaussian order.
void RandomSplatGradients(const std::vector<int>& radius_a,
                          const std::vector<int>& radius_b,
                          std::mt19937& rng,
                          SplatGradients* g) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const std::size_t n = radius_a.size();
  g->SetZero(n, 3);
  for (std::size_t i = 0; i < n; ++i) {
    if (!(radius_a[i] > 0 && radius_b[i] > 0)) continue;
    for (int k = 0; k < 2; ++k) g->mean2d[2 * i + k] = u(rng);
    for (int k = 0; k < 3; ++k) g->conic[3 * i + k] = u(rng);
    g->opacity[i] = u(rng);
    for (int k = 0; k < 3; ++k) g->features[3 * i + k] = u(rng);
  }
}

// Forward and backward of both paths on `model`; every output agrees.
void ExpectPathsAgree(const GaussianModel& model, int sh_degree, unsigned seed) {
  const ViewParams<float> view = ViewParams<float>::FromCamera(TestCamera());
  const RenderOptions options = ColourOptions(sh_degree);
  FrameState fast, ref;
  PreprocessForwardFast(model, view, kTime, options, &fast);
  PreprocessForwardReference(model, view, kTime, options, &ref);
  const std::size_t n = model.size();
  ASSERT_EQ(fast.splats.radius.size(), n);
  // Integer radii may differ by one where a float lands on the other side of a ceil.
  int radius_off = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const int a = fast.splats.radius[i], b = ref.splats.radius[i];
    EXPECT_LE(std::abs(a - b), 1) << "radius of Gaussian " << i;
    EXPECT_EQ(a > 0, b > 0) << "visibility of Gaussian " << i;
    EXPECT_LE(std::abs(fast.screen_radius[i] - ref.screen_radius[i]), 1) << i;
    radius_off += a != b;
  }
  EXPECT_LE(radius_off, static_cast<int>(n / 50 + 1));
  // The per-axis binning radii: within the radius, zero only with it, and tighter than the
  // square for some; they bound the ellipse where alpha reaches 1/255 (Sigma from the conic).
  ASSERT_EQ(fast.splats.reach.size(), 2 * n);
  ASSERT_EQ(ref.splats.reach.size(), 2 * n);
  int tighter = 0;
  for (std::size_t i = 0; i < n; ++i) {
    for (const FrameState* st : {&fast, &ref}) {
      const SplatBuffers& sp = st->splats;
      for (int k = 0; k < 2; ++k) {
        const int r = sp.reach[2 * i + k];
        EXPECT_LE(r, sp.radius[i]) << "reach of Gaussian " << i;
        EXPECT_EQ(r > 0, sp.radius[i] > 0) << "reach of Gaussian " << i;
        if (r == 0) continue;
        tighter += r < sp.radius[i];
        const double a = sp.conic[3 * i], b = sp.conic[3 * i + 1], c = sp.conic[3 * i + 2];
        const double sigma = (k == 0 ? c : a) / (a * c - b * b);
        const double extent = std::sqrt(2.0 * std::log(255.0 * sp.opacity[i]) * sigma);
        if (r < sp.radius[i]) {
          EXPECT_GE(r, extent) << "reach of Gaussian " << i;
        }
      }
    }
    for (int k = 0; k < 2; ++k) {
      EXPECT_LE(std::abs(fast.splats.reach[2 * i + k] - ref.splats.reach[2 * i + k]), 1)
          << "reach of Gaussian " << i;
    }
  }
  if (n >= 100) {
    EXPECT_GT(tighter, 0) << "no Gaussian binned tighter than its square";
  }
  EXPECT_EQ(fast.num_visible, ref.num_visible);
  // Outputs of the visible Gaussians (the rest are unspecified).
  auto visible_rows = [&](const std::vector<float>& v, int width) {
    std::vector<float> out;
    for (std::size_t i = 0; i < n; ++i) {
      if (ref.splats.radius[i] > 0 && fast.splats.radius[i] > 0)
        out.insert(out.end(), v.begin() + i * width, v.begin() + (i + 1) * width);
    }
    return out;
  };
  CountFar(visible_rows(fast.splats.mean2d, 2), visible_rows(ref.splats.mean2d, 2), 2e-3f, 1e-5f,
           "mean2d");
  // The conic against its row's largest entry: an off-diagonal near zero (a needle whose 2D
  // covariance is the dilation alone) is a difference of nearly equal numbers.
  for (std::size_t i = 0; i < n; ++i) {
    if (!(ref.splats.radius[i] > 0 && fast.splats.radius[i] > 0)) continue;
    float row = 0;
    for (int k = 0; k < 3; ++k) row = std::max(row, std::abs(ref.splats.conic[3 * i + k]));
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(fast.splats.conic[3 * i + k], ref.splats.conic[3 * i + k], 2e-4f * row)
          << "conic of Gaussian " << i << ", entry " << k;
    }
  }
  CountFar(visible_rows(fast.splats.depth, 1), visible_rows(ref.splats.depth, 1), 1e-6f, 1e-5f,
           "depth");
  CountFar(visible_rows(fast.splats.opacity, 1), visible_rows(ref.splats.opacity, 1), 1e-6f, 1e-4f,
           "opacity");
  CountFar(visible_rows(fast.splats.features, 3), visible_rows(ref.splats.features, 3), 2e-6f,
           1e-4f, "features");

  // Backward from the same splat gradients (zero where either path culled).
  std::mt19937 rng(seed);
  RandomSplatGradients(ref.splats.radius, fast.splats.radius, rng, &ref.splat_grads);
  fast.splat_grads = ref.splat_grads;
  GaussianGradients g_fast, g_ref;
  g_fast.ZerosLike(model);
  g_ref.ZerosLike(model);
  PreprocessBackwardFast(model, view, kTime, options, fast, &g_fast);
  PreprocessBackwardReference(model, view, kTime, options, ref, &g_ref);
  // Gradients of badly conditioned Gaussians (needles, floored time variance) are large; the
  // absolute tolerance scales with each field's largest value.
  auto max_abs = [](const std::vector<float>& v) {
    float m = 0;
    for (float x : v) m = std::max(m, std::abs(x));
    return m;
  };
  for (const auto& [name, a, b] :
       {std::tuple{"xyz", &g_fast.xyz, &g_ref.xyz}, std::tuple{"t", &g_fast.t, &g_ref.t},
        std::tuple{"log_scales", &g_fast.log_scales, &g_ref.log_scales},
        std::tuple{"rot_left", &g_fast.rot_left, &g_ref.rot_left},
        std::tuple{"rot_right", &g_fast.rot_right, &g_ref.rot_right},
        std::tuple{"opacity_logit", &g_fast.opacity_logit, &g_ref.opacity_logit},
        std::tuple{"color_dc", &g_fast.color_dc, &g_ref.color_dc},
        std::tuple{"color_rest", &g_fast.color_rest, &g_ref.color_rest}}) {
    CountFar(*a, *b, 1e-4f * std::max(1e-3f, max_abs(*b)), 2e-3f, name);
  }
}

TEST(Preprocess, EveryCompiledTargetMatchesTheReference) {
  const GaussianModel model = Scene(300, /*edge_cases=*/true, 11);
  const int ran = ForEachCompiledTarget([&] {
    ExpectPathsAgree(model, 3, 1);
    ExpectPathsAgree(model, 1, 2);  // SH degree still growing: inactive coefficients
  });
  EXPECT_GE(ran, MinimumTargetRuns());  // at least one vector target and the baseline
}

TEST(Preprocess, EdgeCasesAreHandledAlikeAndAsIntended) {
  const GaussianModel model = Scene(0, /*edge_cases=*/true, 12);
  ForEachCompiledTarget([&] { ExpectPathsAgree(model, 3, 3); });
  // The intended outcome, from the reference: behind the near plane and far outside the guard
  // band culled, far from t culled, the floored time variance still finite.
  const ViewParams<float> view = ViewParams<float>::FromCamera(TestCamera());
  RenderOptions options;
  FrameState ref;
  PreprocessForwardReference(model, view, kTime, options, &ref);
  EXPECT_EQ(ref.splats.radius[0], 0) << "0.15 in front of the camera: before the near plane";
  EXPECT_EQ(ref.splats.radius[1], 0) << "0.199: before the near plane";
  for (int i : {16, 17}) EXPECT_EQ(ref.screen_radius[i], 0) << "culled in time: " << i;
  for (std::size_t i = 0; i < model.size(); ++i) {
    if (ref.splats.radius[i] == 0) continue;
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(std::isfinite(ref.splats.conic[3 * i + k])) << i;
    EXPECT_TRUE(std::isfinite(ref.splats.opacity[i])) << i;
  }
}

// The same Gaussians as a 3D model (a static scene's): no time axis, no time block of colour.
GaussianModel Static(GaussianModel m) {
  m.temporal = false;
  m.basis.max_time_degree = 0;
  m.color_rest.resize(m.size() * m.rest_stride());
  // Distinct values in the slots the 3D mode must ignore, so a read of them shows.
  for (std::size_t i = 0; i < m.size(); ++i) {
    m.t[i] = 7.0f;
    m.log_scales[i * 4 + 3] = 3.0f;
    for (int k = 0; k < 4; ++k) m.rot_right[i * 4 + k] = 0.5f + 0.1f * k;
  }
  return m;
}

TEST(Preprocess, StaticModelsMatchTheReferenceOnEveryTarget) {
  const GaussianModel model = Static(Scene(300, /*edge_cases=*/true, 15));
  const int ran = ForEachCompiledTarget([&] {
    ExpectPathsAgree(model, 3, 6);
    ExpectPathsAgree(model, 0, 7);
  });
  EXPECT_GE(ran, MinimumTargetRuns());
  ForEachCompiledTarget([&] { ExpectPathsAgree(Static(Scene(1, false, 16)), 3, 8); });
}

TEST(Preprocess, OneGaussianAndNone) {
  ForEachCompiledTarget([&] {
    ExpectPathsAgree(Scene(1, false, 13), 3, 4);
    ExpectPathsAgree(Scene(0, false, 14), 3, 5);
  });
}

// The conditional Gaussians are the reference backward's cache (216 bytes each): the fast path
// neither fills nor keeps them, even in a state a reference frame used before.
TEST(Preprocess, TheFastPathHoldsNoConditionalGaussians) {
  const GaussianModel model = Scene(500, false, 21);
  const ViewParams<float> view = ViewParams<float>::FromCamera(TestCamera());
  RenderOptions options;
  FrameState state;
  PreprocessForwardReference(model, view, kTime, options, &state);
  EXPECT_EQ(state.conditionals.size(), model.size());
  PreprocessForwardFast(model, view, kTime, options, &state);
  EXPECT_EQ(state.conditionals.capacity(), 0u);
  EXPECT_GT(state.num_visible, 0u);
}

GaussianModelT<double> ToDouble(const GaussianModel& m) {
  GaussianModelT<double> d;
  d.temporal = m.temporal;
  d.color_mode = m.color_mode;
  d.basis = m.basis;
  d.channels = m.channels;
  auto copy = [](const std::vector<float>& v) { return std::vector<double>(v.begin(), v.end()); };
  d.xyz = copy(m.xyz), d.t = copy(m.t), d.log_scales = copy(m.log_scales);
  d.rot_left = copy(m.rot_left), d.rot_right = copy(m.rot_right);
  d.opacity_logit = copy(m.opacity_logit), d.color_dc = copy(m.color_dc);
  d.color_rest = copy(m.color_rest);
  return d;
}

// Every parameter buffer of a model (or of its gradient), in one order.
template <typename T>
std::vector<std::vector<T>*> ParameterBuffers(GaussianModelT<T>& m) {
  return {&m.xyz, &m.t, &m.log_scales, &m.rot_left, &m.rot_right,
          &m.opacity_logit, &m.color_dc, &m.color_rest};
}

// FastBackward (preprocess_fast.cpp), the whole fast backward behind PreprocessBackwardFast: the
// gradient of every parameter buffer of a 4D and a 3D model against central differences in
// double of the reference forward, on every compiled target, with the colour rows written to
// the gradient and handed over through rows_done. The loss dots fixed random splat gradients
// (mean2d, conic, opacity, features) of the Gaussians the fast forward kept with the splat
// outputs (the colour's view direction and dt detached, as the reference does), so its gradient
// is exactly what the backward computes. Tolerance: float arithmetic in the kernels against
// double differences, 2e-3 of the largest component.
TEST(Preprocess, FastBackwardMatchesFiniteDifferencesInDouble) {
  for (bool temporal : {true, false}) {
    SCOPED_TRACE(temporal ? "4D" : "3D");
    GaussianModel model = Scene(5, false, temporal ? 21 : 22);
    if (!temporal) model = Static(model);
    const RenderOptions options = ColourOptions(1);
    FrameState fast;
    PreprocessForwardFast(model, ViewParams<float>::FromCamera(TestCamera()), kTime, options,
                          &fast);
    std::mt19937 rng(6);
    RandomSplatGradients(fast.splats.radius, fast.splats.radius, rng, &fast.splat_grads);
    const std::size_t n = model.size();
    std::size_t visible = 0;
    for (std::size_t i = 0; i < n; ++i) visible += fast.splats.radius[i] > 0;
    ASSERT_GE(visible, 3u);
    const ViewParams<double> view = ViewParams<double>::FromCamera(TestCamera());
    GaussianModelT<double> base = ToDouble(model);
    const auto flatten = [](GaussianModelT<double>& m) {
      std::vector<double> all;
      for (const std::vector<double>* b : ParameterBuffers(m))
        all.insert(all.end(), b->begin(), b->end());
      return all;
    };
    const std::vector<double> x0 = flatten(base);
    // The colour's view direction and dt are detached (sh4d.h), so the features term reads the
    // colours of `x` on the base geometry.
    const auto loss = [&](const testing::FdVector& x) {
      GaussianModelT<double> m = base;
      int k = 0;
      for (std::vector<double>* b : ParameterBuffers(m))
        for (double& v : *b) v = x(k++);
      GaussianModelT<double> colours = base;
      colours.color_dc = m.color_dc;
      colours.color_rest = m.color_rest;
      FrameStateT<double> state, colour_state;
      PreprocessForwardReference(m, view, double(kTime), options, &state);
      PreprocessForwardReference(colours, view, double(kTime), options, &colour_state);
      state.splats.features = colour_state.splats.features;
      const SplatGradients& g = fast.splat_grads;
      double l = 0;
      for (std::size_t i = 0; i < n; ++i) {
        if (fast.splats.radius[i] <= 0) continue;
        for (int k = 0; k < 2; ++k) l += g.mean2d[2 * i + k] * state.splats.mean2d[2 * i + k];
        for (int k = 0; k < 3; ++k) l += g.conic[3 * i + k] * state.splats.conic[3 * i + k];
        l += g.opacity[i] * state.splats.opacity[i];
        for (int k = 0; k < 3; ++k) l += g.features[3 * i + k] * state.splats.features[3 * i + k];
      }
      return l;
    };
    constexpr testing::FdCheck kFd{1e-6, 2e-3};
    const testing::FdVector x = Eigen::Map<const testing::FdVector>(x0.data(), x0.size());
    const testing::FdVector numeric = kFd.Gradient(loss, x);
    ASSERT_GT(numeric.cwiseAbs().maxCoeff(), 1e-2);
    const int ran = ForEachCompiledTarget([&] {
      GaussianGradients g;
      g.ZerosLike(model);
      PreprocessBackwardFast(model, ViewParams<float>::FromCamera(TestCamera()), kTime, options,
                             fast, &g);
      GaussianModelT<double> gd = ToDouble(g);
      const std::vector<double> analytic = flatten(gd);
      kFd.ExpectMatch(Eigen::Map<const testing::FdVector>(analytic.data(), analytic.size()),
                      numeric);
      // Again with the colour rows handed over from FastBackward's per-thread block.
      GaussianGradients g_done;
      g_done.ZerosLike(model, /*colour=*/false);
      const std::size_t channels = model.channels, stride = model.rest_stride();
      std::vector<float> dc(model.color_dc.size(), -1.0f), rest(model.color_rest.size(), -1.0f);
      PreprocessBackwardFast(
          model, ViewParams<float>::FromCamera(TestCamera()), kTime, options, fast, &g_done,
          [&](std::int64_t b, std::int64_t e, const GradientRows& rows) {  // disjoint ranges
            std::copy_n(rows.color_dc, (e - b) * channels, dc.begin() + b * channels);
            std::copy_n(rows.color_rest, (e - b) * stride, rest.begin() + b * stride);
          });
      g_done.color_dc = dc;
      g_done.color_rest = rest;
      GaussianModelT<double> gd_done = ToDouble(g_done);
      const std::vector<double> analytic_done = flatten(gd_done);
      kFd.ExpectMatch(
          Eigen::Map<const testing::FdVector>(analytic_done.data(), analytic_done.size()),
          numeric);
    });
    EXPECT_GE(ran, MinimumTargetRuns());
  }
}

// NormalizeBackward (preprocess_simd.cpp), the fast path's backward through the normalisation
// of both quaternions: its gradient with respect to the stored, unnormalised quaternions against
// central differences in double of the reference forward, on every compiled target. The loss
// dots fixed random splat gradients with the splat outputs, so its gradient is exactly what the
// backward receives.
TEST(Preprocess, NormalizeBackwardMatchesFiniteDifferencesInDouble) {
  GaussianModel model = Scene(6, false, 11);
  for (std::size_t i = 0; i < model.rot_left.size(); ++i) {
    model.rot_left[i] *= 1.7f;   // lengths away from 1: the normalisation matters
    model.rot_right[i] *= 0.6f;
  }
  const std::size_t n = model.size();
  const RenderOptions options = ColourOptions(1);
  FrameState fast;
  PreprocessForwardFast(model, ViewParams<float>::FromCamera(TestCamera()), kTime, options, &fast);
  std::mt19937 rng(5);
  RandomSplatGradients(fast.splats.radius, fast.splats.radius, rng, &fast.splat_grads);
  const ViewParams<double> view = ViewParams<double>::FromCamera(TestCamera());
  const GaussianModelT<double> base = ToDouble(model);
  // The loss of one quaternion entry's value (the rest of the model as it is).
  auto loss = [&](bool left, std::size_t index, double value) {
    GaussianModelT<double> m = base;
    (left ? m.rot_left : m.rot_right)[index] = value;
    FrameStateT<double> state;
    PreprocessForwardReference(m, view, double(kTime), options, &state);
    double l = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (fast.splats.radius[i] <= 0) continue;
      for (int k = 0; k < 2; ++k) l += fast.splat_grads.mean2d[2 * i + k] * state.splats.mean2d[2 * i + k];
      for (int k = 0; k < 3; ++k) l += fast.splat_grads.conic[3 * i + k] * state.splats.conic[3 * i + k];
      l += fast.splat_grads.opacity[i] * state.splats.opacity[i];
      for (int k = 0; k < 3; ++k)
        l += fast.splat_grads.features[3 * i + k] * state.splats.features[3 * i + k];
    }
    return l;
  };
  constexpr double kStep = 1e-6;
  std::vector<double> numeric_left(4 * n), numeric_right(4 * n);
  for (bool left : {true, false}) {
    const std::vector<double>& q = left ? base.rot_left : base.rot_right;
    for (std::size_t j = 0; j < 4 * n; ++j) {
      (left ? numeric_left : numeric_right)[j] =
          (loss(left, j, q[j] + kStep) - loss(left, j, q[j] - kStep)) / (2 * kStep);
    }
  }
  // The check must see real gradients: visible Gaussians whose loss moves with the quaternions.
  std::size_t visible = 0;
  double largest = 0;
  for (std::size_t i = 0; i < n; ++i) visible += fast.splats.radius[i] > 0;
  for (double v : numeric_left) largest = std::max(largest, std::abs(v));
  ASSERT_GE(visible, 3u);
  ASSERT_GT(largest, 1e-2);
  const int ran = ForEachCompiledTarget([&] {
    GaussianGradients g;
    g.ZerosLike(model);
    PreprocessBackwardFast(model, ViewParams<float>::FromCamera(TestCamera()), kTime, options,
                           fast, &g);
    for (std::size_t j = 0; j < 4 * n; ++j) {
      if (fast.splats.radius[j / 4] <= 0) continue;
      EXPECT_NEAR(g.rot_left[j], numeric_left[j], 2e-3 * (1 + std::abs(numeric_left[j]))) << j;
      EXPECT_NEAR(g.rot_right[j], numeric_right[j], 2e-3 * (1 + std::abs(numeric_right[j]))) << j;
    }
  });
  EXPECT_GE(ran, 1);
}

// Gaussians whose marginal p(t) straddles the cull threshold: times spread around kTime, time
// scales of 0.03-0.3 and rotations that mix time and space, so Sigma_tt is not the 4th scale.
GaussianModel TimeSpread(int count, unsigned seed) {
  GaussianModel m = Scene(count, false, seed);
  std::mt19937 rng(seed + 1);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int i = 0; i < count; ++i) {
    m.t[i] = kTime + 0.6f * u(rng);
    m.log_scales[4 * i + 3] = std::log(0.03f) + 1.15f * (u(rng) + 1.0f);
    for (int k = 0; k < 4; ++k) m.rot_right[4 * i + k] = u(rng);
  }
  m.rot_right[0] = m.rot_right[1] = m.rot_right[2] = m.rot_right[3] =
      0.0f;  // the identity fallback
  // Extremes the early test must keep or cull exactly as the full one: a huge and a tiny time
  // scale (the variance floor), long and short quaternions, a time far away, at two offsets.
  for (int i : {count - 40, count - 23}) {
    m.log_scales[4 * (i + 0) + 3] = 45.0f;
    m.log_scales[4 * (i + 1) + 3] = -60.0f;
    m.t[i + 1] = kTime + 1e-20f;
    m.log_scales[4 * (i + 2) + 3] = -60.0f;
    for (int k = 0; k < 4; ++k) m.rot_right[4 * (i + 3) + k] *= 1e4f;
    for (int k = 0; k < 4; ++k) m.rot_left[4 * (i + 4) + k] *= 1e-3f;
    m.t[i + 5] = 1e19f;
    m.log_scales[4 * (i + 6) + 0] = 41.0f;
  }
  return m;
}

// The forward's outputs of every Gaussian, `index` in batches of kPreprocessBatch.
struct JobOutputs {
  explicit JobOutputs(std::size_t n)
      : mean2d(2 * n, -7),
        conic(3 * n, -7),
        depth(n, -7),
        opacity(n, -7),
        radius(n, -7),
        reach(2 * n, -7),
        screen(n, -7) {}
  void Bind(detail::PreprocessSimdJob* job) {
    job->mean2d = mean2d.data(), job->conic = conic.data(), job->depth = depth.data();
    job->opacity = opacity.data(), job->radius = radius.data(), job->reach = reach.data();
    job->screen_radius = screen.data();
  }
  std::vector<float> mean2d, conic, depth, opacity;
  std::vector<int> radius, reach, screen;
};

void ForwardBatches(const detail::PreprocessSimdJob& job, const std::vector<std::int64_t>& index) {
  alignas(64) float weights[kMaxColorCoefficients * detail::kPreprocessBatch];  // aligned stores
  for (std::size_t k = 0; k < index.size(); k += detail::kPreprocessBatch) {
    const int count =
        static_cast<int>(std::min<std::size_t>(detail::kPreprocessBatch, index.size() - k));
    detail::PreprocessForwardSimd(job, index.data() + k, count, weights);
  }
}

// The cull by time ahead of the geometry (PreprocessTemporalSurvivors) removes only Gaussians the
// full forward removes, and its outputs for them are the full forward's: on every target, over
// chunks that end mid-vector, the results are those of the forward run on every Gaussian, to the
// bit. It must also remove most of what is far from the threshold, or it saves nothing.
TEST(Preprocess, TheCullByTimeRemovesOnlyWhatTheFullForwardRemoves) {
  const GaussianModel model = TimeSpread(3001, 31);
  const std::size_t n = model.size();
  const RenderOptions options = ColourOptions(3);
  const ViewParams<float> view = ViewParams<float>::FromCamera(TestCamera());
  const int ran = ForEachCompiledTarget([&] {
    detail::PreprocessSimdJob job = detail::MakePreprocessJob(model, view, kTime, options);
    JobOutputs all(n), culled_first(n);
    all.Bind(&job);
    std::vector<std::int64_t> every(n);
    for (std::size_t i = 0; i < n; ++i) every[i] = static_cast<std::int64_t>(i);
    ForwardBatches(job, every);

    culled_first.Bind(&job);
    std::vector<std::int64_t> survivors;
    for (std::int64_t begin = 0; begin < static_cast<std::int64_t>(n); begin += 1000) {
      const int count = static_cast<int>(std::min<std::int64_t>(1000, n - begin));
      std::vector<std::int64_t> kept(count);
      kept.resize(detail::PreprocessTemporalSurvivors(job, begin, count, kept.data()));
      survivors.insert(survivors.end(), kept.begin(), kept.end());
    }
    ASSERT_TRUE(std::is_sorted(survivors.begin(), survivors.end()));
    ForwardBatches(job, survivors);
    EXPECT_EQ(culled_first.radius, all.radius);
    EXPECT_EQ(culled_first.reach, all.reach);
    EXPECT_EQ(culled_first.screen, all.screen);
    std::size_t visible = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (all.screen[i] == 0) continue;
      ++visible;
      for (int k = 0; k < 2; ++k) EXPECT_EQ(culled_first.mean2d[2 * i + k], all.mean2d[2 * i + k]);
      for (int k = 0; k < 3; ++k) EXPECT_EQ(culled_first.conic[3 * i + k], all.conic[3 * i + k]);
      EXPECT_EQ(culled_first.depth[i], all.depth[i]);
      EXPECT_EQ(culled_first.opacity[i], all.opacity[i]);
    }
    // The scene straddles the threshold: some visible, many culled in time, most of those early.
    const std::size_t removed_early = n - survivors.size();
    EXPECT_GT(visible, n / 5);
    EXPECT_GT(removed_early, n / 4);
    EXPECT_LE(survivors.size(), visible + (n - visible) / 4);
  });
  EXPECT_GE(ran, MinimumTargetRuns());
}

// The backward writes every Gaussian's gradient rows, zero for the culled ones, whatever the
// buffers held before (the kernel runs on the visible Gaussians alone), directly and through the
// rows-done callback.
TEST(Preprocess, TheBackwardZeroesTheCulledGaussiansRows) {
  const GaussianModel model = TimeSpread(700, 33);
  const std::size_t n = model.size();
  const RenderOptions options = ColourOptions(2);
  const ViewParams<float> view = ViewParams<float>::FromCamera(TestCamera());
  FrameState state;
  PreprocessForwardFast(model, view, kTime, options, &state);
  std::mt19937 rng(9);
  RandomSplatGradients(state.splats.radius, state.splats.radius, rng, &state.splat_grads);
  const std::size_t visible = static_cast<std::size_t>(
      std::count_if(state.splats.radius.begin(), state.splats.radius.end(),
                    [](int r) { return r > 0; }));
  ASSERT_GT(visible, n / 5);
  ASSERT_LT(visible, n - n / 5);
  ForEachCompiledTarget([&] {
    GaussianGradients clean, dirty;
    clean.ZerosLike(model);
    dirty.ZerosLike(model);
    for (std::vector<float>* v :
         {&dirty.xyz, &dirty.t, &dirty.log_scales, &dirty.rot_left, &dirty.rot_right,
          &dirty.opacity_logit, &dirty.color_dc, &dirty.color_rest})
      std::fill(v->begin(), v->end(), 9.0f);
    PreprocessBackwardFast(model, view, kTime, options, state, &clean);
    PreprocessBackwardFast(model, view, kTime, options, state, &dirty);
    EXPECT_EQ(dirty.xyz, clean.xyz);
    EXPECT_EQ(dirty.t, clean.t);
    EXPECT_EQ(dirty.log_scales, clean.log_scales);
    EXPECT_EQ(dirty.rot_left, clean.rot_left);
    EXPECT_EQ(dirty.rot_right, clean.rot_right);
    EXPECT_EQ(dirty.opacity_logit, clean.opacity_logit);
    EXPECT_EQ(dirty.color_dc, clean.color_dc);
    EXPECT_EQ(dirty.color_rest, clean.color_rest);
    // Through the callback: the same rows, every row handed over once, in blocks.
    std::vector<float> dc(clean.color_dc.size(), 9.0f), rest(clean.color_rest.size(), 9.0f);
    std::vector<int> handed(n, 0);
    const std::size_t stride = model.rest_stride();
    GaussianGradients geometry;
    geometry.ZerosLike(model);
    geometry.color_dc.clear();
    geometry.color_rest.clear();
    std::fill(geometry.xyz.begin(), geometry.xyz.end(), 9.0f);
    std::mutex mutex;
    PreprocessBackwardFast(model, view, kTime, options, state, &geometry,
                           [&](std::int64_t begin, std::int64_t end, const GradientRows& rows) {
                             std::lock_guard<std::mutex> lock(mutex);
                             for (std::int64_t i = begin; i < end; ++i) {
                               ++handed[i];
                               const std::size_t r = static_cast<std::size_t>(i - begin);
                               std::copy_n(rows.color_dc + r * 3, 3, dc.begin() + i * 3);
                               std::copy_n(rows.color_rest + r * stride, stride,
                                           rest.begin() + i * stride);
                             }
                           });
    EXPECT_EQ(handed, std::vector<int>(n, 1));
    EXPECT_EQ(dc, clean.color_dc);
    EXPECT_EQ(rest, clean.color_rest);
    EXPECT_EQ(geometry.xyz, clean.xyz);
  });
}

// Frame f's colour rows through the rows-done callback against the direct (full-buffer)
// backward's, on every compiled target, the frames run in order on the same threads.
void ExpectCallbackRowsMatchDirect(const GaussianModel& model,
                                   const std::vector<float>& times,
                                   const std::vector<RenderOptions>& options,
                                   std::uint32_t seed) {
  const std::size_t stride = model.rest_stride();
  const ViewParams<float> view = ViewParams<float>::FromCamera(TestCamera());
  std::vector<FrameState> states(times.size());
  std::mt19937 rng(seed);
  for (std::size_t f = 0; f < states.size(); ++f) {
    PreprocessForwardFast(model, view, times[f], options[f], &states[f]);
    RandomSplatGradients(states[f].splats.radius, states[f].splats.radius, rng,
                         &states[f].splat_grads);
  }
  ForEachCompiledTarget([&] {
    for (std::size_t f = 0; f < states.size(); ++f) {
      GaussianGradients direct;
      direct.ZerosLike(model);
      PreprocessBackwardFast(model, view, times[f], options[f], states[f], &direct);
      std::vector<float> dc(direct.color_dc.size(), 9.0f), rest(direct.color_rest.size(), 9.0f);
      GaussianGradients geometry;
      geometry.ZerosLike(model);
      geometry.color_dc.clear();
      geometry.color_rest.clear();
      std::mutex mutex;
      PreprocessBackwardFast(model, view, times[f], options[f], states[f], &geometry,
                             [&](std::int64_t begin, std::int64_t end, const GradientRows& rows) {
                               std::lock_guard<std::mutex> lock(mutex);
                               const std::size_t b = static_cast<std::size_t>(begin);
                               const std::size_t count = static_cast<std::size_t>(end - begin);
                               std::copy_n(rows.color_dc, 3 * count, dc.begin() + 3 * b);
                               std::copy_n(rows.color_rest, stride * count,
                                           rest.begin() + stride * b);
                             });
      EXPECT_EQ(dc, direct.color_dc) << "frame " << f;
      EXPECT_EQ(rest, direct.color_rest) << "frame " << f;
    }
  });
}

// The colour rows handed to the callback stay right from frame to frame while the culled set
// changes: the backward reuses its per-thread block and skips re-zeroing the rows it knows are
// zero, so a row written for a visible Gaussian must be zeroed when a culled one takes its place.
TEST(Preprocess, TheCallbackRowsFollowTheCulledSetFromFrameToFrame) {
  const GaussianModel model = TimeSpread(700, 34);
  const std::vector<float> times = {kTime - 0.4f, kTime + 0.4f, kTime, kTime - 0.4f};
  const RenderOptions options = ColourOptions(2);
  // The frames differ in which Gaussians are culled.
  const ViewParams<float> view = ViewParams<float>::FromCamera(TestCamera());
  FrameState a, b;
  PreprocessForwardFast(model, view, times[0], options, &a);
  PreprocessForwardFast(model, view, times[1], options, &b);
  ASSERT_NE(a.splats.radius, b.splats.radius);
  ExpectCallbackRowsMatchDirect(model, times, std::vector<RenderOptions>(times.size(), options),
                                10);
}

// The callback's rows are written only as far as the colour degrees reach (the block's tail
// stays zero), so when the degrees drop (a probe ends, another model follows on the same
// threads) the longer rows of an earlier frame must not show through.
TEST(Preprocess, TheCallbackRowsFollowTheColourDegreesDownAsWellAsUp) {
  const GaussianModel model = TimeSpread(700, 35);
  const std::pair<int, int> degrees[] = {{0, 0}, {3, 2}, {0, 0}, {1, 1}, {0, 1}, {2, 0}, {0, 0}};
  std::vector<float> times;
  std::vector<RenderOptions> options;
  for (const auto& [sh, time] : degrees) {
    RenderOptions o = ColourOptions(sh);
    o.time_degree = time;
    options.push_back(o);
    times.push_back(kTime + 0.05f * static_cast<float>(times.size() % 3));
  }
  ExpectCallbackRowsMatchDirect(model, times, options, 11);
}

}  // namespace
}  // namespace hdr4d::method
