#include "method/optim/time_order.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "core/geometry/camera.h"
#include "method/gaussian/constants.h"
#include "method/optim/permute_rows.h"
#include "method/render/frame_render.h"

namespace hdr4d::method {
namespace {

// sqrt(2 ln(1 / threshold)): a window's half-width in units of the time standard deviation.
const double kHalfWidth = std::sqrt(2.0 * std::log(1.0 / kTemporalCullMarginal));

std::vector<std::uint32_t> RandomOrder(std::size_t n, std::mt19937& rng) {
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::shuffle(order.begin(), order.end(), rng);
  return order;
}

// Gaussians with unrotated axes (Sigma_tt = sigma_t^2), time means t, small spatial scales in
// front of Camera() below, and random opacities and colours (SH degree 1, time degree 1).
GaussianModel WindowModel(const std::vector<float>& t,
                          const std::vector<float>& sigma_t,
                          unsigned seed) {
  GaussianModel m;
  m.temporal = true;
  m.basis = {1, 1};
  m.channels = 3;
  m.Resize(t.size());
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (std::size_t i = 0; i < t.size(); ++i) {
    for (int a = 0; a < 3; ++a) m.xyz[3 * i + a] = 0.6f * u(rng);
    m.t[i] = t[i];
    for (int a = 0; a < 3; ++a) m.log_scales[4 * i + a] = std::log(0.15f + 0.05f * u(rng));
    m.log_scales[4 * i + 3] = std::log(sigma_t[i]);
    m.rot_left[4 * i] = m.rot_right[4 * i] = 1.0f;  // the identity rotation
    m.opacity_logit[i] = u(rng);
    for (int c = 0; c < 3; ++c) m.color_dc[3 * i + c] = 1.0f + 0.5f * u(rng);
  }
  for (float& v : m.color_rest) v = 0.1f * u(rng);
  return m;
}

Camera TestCamera() {
  return Camera{PinholeIntrinsics::FromFovX(0.9, 32, 24),
                LookAtWorldFromCamGl({0.2, -4.0, 0.5}, {0, 0, 0}, Eigen::Vector3d::UnitZ())};
}

TEST(PermuteRowsInPlace, MatchesAGatherForEveryShapeOfCycles) {
  std::mt19937 rng(3);
  for (std::size_t n : {1u, 2u, 5u, 64u, 1000u}) {
    for (std::size_t width : {0u, 1u, 3u, 7u}) {
      std::vector<float> data(n * width);
      for (std::size_t k = 0; k < data.size(); ++k) data[k] = static_cast<float>(k);
      const std::vector<std::uint32_t> order = RandomOrder(n, rng);
      ASSERT_TRUE(IsPermutation(order));
      std::vector<float> gathered;
      for (const std::uint32_t from : order)
        gathered.insert(gathered.end(), data.begin() + from * width,
                        data.begin() + (from + 1) * width);
      PermuteRowsInPlace(data.data(), width, order);
      EXPECT_EQ(data, gathered) << n << " rows of " << width;
    }
  }
  // One cycle through every row, and the identity.
  std::vector<float> rows = {0, 1, 2, 3, 4};
  PermuteRowsInPlace(rows.data(), 1, std::vector<std::uint32_t>{1, 2, 3, 4, 0});
  EXPECT_EQ(rows, (std::vector<float>{1, 2, 3, 4, 0}));
  PermuteRowsInPlace(rows.data(), 1, std::vector<std::uint32_t>{0, 1, 2, 3, 4});
  EXPECT_EQ(rows, (std::vector<float>{1, 2, 3, 4, 0}));
}

TEST(PermuteRowsInPlace, IsPermutationRejectsRepeatsAndRowsOutOfRange) {
  EXPECT_TRUE(IsPermutation(std::vector<std::uint32_t>{}));
  EXPECT_TRUE(IsPermutation(std::vector<std::uint32_t>{2, 0, 1}));
  EXPECT_FALSE(IsPermutation(std::vector<std::uint32_t>{0, 0, 1}));
  EXPECT_FALSE(IsPermutation(std::vector<std::uint32_t>{0, 1, 3}));
}

TEST(VisibleTimeOrder, SortsByTheOpeningOfTheWindowClampedToTheScene) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  // Windows open at: 0.9 - w 0.01, 0.2 - w 0.01, long before 0 (static), 0.5 - w 0.01,
  // NaN, after the scene's last time (1.5 - w 0.01), 0.2 - w 0.01 again (a tie with row 1).
  const GaussianModel m = WindowModel({0.9f, 0.2f, 0.5f, 0.5f, nan, 1.5f, 0.2f},
                                      {0.01f, 0.01f, 10.0f, 0.01f, 0.01f, 0.01f, 0.01f}, 1);
  EXPECT_EQ(VisibleTimeOrder(m, 0.0f, 1.0f), (std::vector<std::uint32_t>{2, 4, 1, 6, 3, 0, 5}));
  // Clamped to the scene's range: every window opens at 0 in a scene of times [0.95, 1], and
  // the ties keep the current order.
  EXPECT_EQ(VisibleTimeOrder(m, 0.95f, 1.0f), (std::vector<std::uint32_t>{0, 1, 2, 3, 4, 6, 5}));
}

// The point of the order: with windows of one width, the Gaussians a frame keeps (p(t) above
// the renderer's threshold) are one run of consecutive rows at every time.
TEST(VisibleTimeOrder, AFramesGaussiansAreConsecutiveRows) {
  std::mt19937 rng(5);
  // Inside [0.1, 0.9], so that no window is clamped to the scene's range.
  std::uniform_real_distribution<float> u(0.1f, 0.9f);
  std::vector<float> t(500);
  for (float& v : t) v = u(rng);
  const float sigma = 0.03f;
  GaussianModel m = WindowModel(t, std::vector<float>(t.size(), sigma), 2);
  ReorderGaussians(VisibleTimeOrder(m, 0.0f, 1.0f), &m, nullptr, nullptr);
  for (float time = 0.1f; time <= 0.9f; time += 0.05f) {
    std::vector<std::size_t> kept;
    for (std::size_t i = 0; i < m.size(); ++i) {
      if (std::abs(time - m.t[i]) < kHalfWidth * sigma) kept.push_back(i);
    }
    ASSERT_FALSE(kept.empty());
    EXPECT_EQ(kept.back() - kept.front() + 1, kept.size()) << "time " << time;
  }
}

TEST(ReorderGaussians, MovesEveryBufferMomentAndStatisticAndKeepsTheBindings) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const std::size_t n = 300;
  std::vector<float> t(n), sigma(n);
  for (std::size_t i = 0; i < n; ++i) {
    t[i] = 0.5f + 0.5f * u(rng);
    sigma[i] = 0.05f + 0.04f * u(rng);
  }
  GaussianModel m = WindowModel(t, sigma, 3);
  GaussianGradients grads;
  grads.ZerosLike(m);
  Adam adam;
  AddModelGroups(m, grads, {1e-3f, 1e-3f, 1e-3f, 1e-3f, 1e-3f, 1e-3f, 1e-3f}, &adam);
  for (const char* name : kModelGroups) {
    float* g = const_cast<float*>(adam.group(name).grads);
    for (std::size_t k = 0; k < adam.group(name).size; ++k) g[k] = u(rng);
  }
  adam.Step();  // non-zero moments
  DensifyStats stats;
  stats.Reset(n);
  for (std::size_t i = 0; i < n; ++i) {
    stats.grad_accum[i] = u(rng);
    stats.denom[i] = static_cast<float>(i);
    stats.max_radii[i] = u(rng);
  }
  GaussianModel before = m;
  const Adam adam_before = adam;
  const DensifyStats stats_before = stats;
  const std::vector<std::uint32_t> order = RandomOrder(n, rng);
  ReorderGaussians(order, &m, &adam, &stats);

  const auto now = ModelGroupBuffers(m);
  const auto old = ModelGroupBuffers(before);
  for (std::size_t k = 0; k < kModelGroups.size(); ++k) {
    const char* name = kModelGroups[k];
    const std::size_t w = GroupRowWidth(m, name);
    EXPECT_EQ(adam.group(name).params, now[k]->data()) << name;  // still bound, not reallocated
    for (std::size_t row = 0; row < n; ++row) {
      for (std::size_t c = 0; c < w; ++c) {
        const std::size_t to = row * w + c, from = order[row] * w + c;
        ASSERT_EQ((*now[k])[to], (*old[k])[from]) << name;
        ASSERT_EQ(adam.FirstMoment(name)[to], adam_before.FirstMoment(name)[from]) << name;
        ASSERT_EQ(adam.SecondMoment(name)[to], adam_before.SecondMoment(name)[from]) << name;
      }
    }
    EXPECT_EQ(adam.StepCount(name), adam_before.StepCount(name));
  }
  for (std::size_t row = 0; row < n; ++row) {
    EXPECT_EQ(stats.grad_accum[row], stats_before.grad_accum[order[row]]);
    EXPECT_EQ(stats.denom[row], stats_before.denom[order[row]]);
    EXPECT_EQ(stats.max_radii[row], stats_before.max_radii[order[row]]);
  }
}

// Adam's update is per element: reordering then stepping equals stepping then reordering, bit
// for bit, so a reorder moves no parameter.
TEST(ReorderGaussians, CommutesWithAnAdamStep) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const std::size_t n = 257;
  std::vector<float> t(n), sigma(n, 0.1f);
  for (float& v : t) v = u(rng);
  struct Run {
    GaussianModel model;
    GaussianGradients grads;
    Adam adam;
  };
  Run a, b;
  a.model = b.model = WindowModel(t, sigma, 4);
  for (Run* r : {&a, &b}) {
    r->grads.ZerosLike(r->model);
    AddModelGroups(r->model, r->grads, {1e-3f, 2e-3f, 3e-3f, 1e-3f, 5e-3f, 1e-2f, 1e-3f}, &r->adam);
  }
  for (std::vector<float>* g : ModelGroupBuffers(a.grads)) {
    for (float& v : *g) v = u(rng);
  }
  b.grads = a.grads;
  BindModelGroups(b.model, b.grads, &b.adam);
  const std::vector<std::uint32_t> order = VisibleTimeOrder(a.model, -1.0f, 1.0f);
  a.adam.Step();
  ReorderGaussians(order, &a.model, &a.adam, nullptr);
  ReorderGaussians(order, &b.model, &b.adam, nullptr);
  // The gradients follow their Gaussians too.
  const auto grads_b = ModelGroupBuffers(b.grads);
  for (std::size_t k = 0; k < kModelGroups.size(); ++k) {
    PermuteRowsInPlace(grads_b[k]->data(), GroupRowWidth(b.model, kModelGroups[k]), order);
  }
  b.adam.Step();
  const auto pa = ModelGroupBuffers(a.model), pb = ModelGroupBuffers(b.model);
  for (std::size_t k = 0; k < kModelGroups.size(); ++k) {
    EXPECT_EQ(*pa[k], *pb[k]) << kModelGroups[k];
    EXPECT_EQ(a.adam.FirstMoment(kModelGroups[k]), b.adam.FirstMoment(kModelGroups[k]));
    EXPECT_EQ(a.adam.SecondMoment(kModelGroups[k]), b.adam.SecondMoment(kModelGroups[k]));
  }
}

// The renderer's output depends on the order only through the rounding of its sums and the
// order of Gaussians at equal depth.
TEST(ReorderGaussians, RendersTheSameImage) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const std::size_t n = 400;
  std::vector<float> t(n), sigma(n);
  for (std::size_t i = 0; i < n; ++i) {
    t[i] = u(rng);
    sigma[i] = 0.02f + 0.3f * u(rng);
  }
  GaussianModel m = WindowModel(t, sigma, 6);
  RenderOptions options;
  options.sh_degree = 1;
  options.time_degree = 1;
  options.background = {0.1f, 0.2f, 0.3f};
  const Camera camera = TestCamera();
  const std::size_t values = 32 * 24 * 3;
  for (const float time : {0.1f, 0.5f, 0.93f}) {
    FrameState state;
    std::vector<float> image(values), reordered(values);
    RenderForward(m, camera, time, options, &state, image.data());
    EXPECT_GT(state.num_visible, 20u);
    GaussianModel sorted = m;
    ReorderGaussians(VisibleTimeOrder(sorted, 0.0f, 1.0f), &sorted, nullptr, nullptr);
    FrameState sorted_state;
    RenderForward(sorted, camera, time, options, &sorted_state, reordered.data());
    EXPECT_EQ(sorted_state.num_visible, state.num_visible);
    double max_diff = 0, max_value = 0;
    for (std::size_t k = 0; k < values; ++k) {
      max_diff = std::max(max_diff, static_cast<double>(std::abs(image[k] - reordered[k])));
      max_value = std::max(max_value, static_cast<double>(std::abs(image[k])));
    }
    EXPECT_GT(max_value, 0.3);
    EXPECT_LT(max_diff, 1e-5) << "time " << time;
  }
}

TEST(ReorderGaussians, RejectsAnOrderThatIsNotAPermutation) {
  GaussianModel m = WindowModel({0.1f, 0.2f, 0.3f}, {0.1f, 0.1f, 0.1f}, 8);
  EXPECT_DEATH(ReorderGaussians({0, 0, 1}, &m, nullptr, nullptr), "internal check failed");
  EXPECT_DEATH(ReorderGaussians({0, 1}, &m, nullptr, nullptr), "internal check failed");
}

}  // namespace
}  // namespace hdr4d::method
