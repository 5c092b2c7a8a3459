#include "method/optim/fused_adam_step.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "method/optim/densify.h"
#include "method/optim/model_optimizer.h"
#include "method/render/frame_render.h"

namespace hdr4d::method {
namespace {

GaussianModel RandomModel(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1, 1);
  GaussianModel m;
  m.Resize(n);
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) m.xyz[i * 3 + a] = 0.7f * u(rng);
    m.t[i] = 0.5f + 0.2f * u(rng);
    for (int a = 0; a < 3; ++a) m.log_scales[i * 4 + a] = std::log(0.05f + 0.02f * u(rng));
    m.log_scales[i * 4 + 3] = std::log(0.4f);
    for (int a = 0; a < 4; ++a) {
      m.rot_left[i * 4 + a] = u(rng) + (a == 0 ? 1.5f : 0.0f);
      m.rot_right[i * 4 + a] = u(rng) + (a == 0 ? 1.5f : 0.0f);
    }
    m.opacity_logit[i] = u(rng);
    for (int c = 0; c < 3; ++c) m.color_dc[i * 3 + c] = 0.5f + 0.5f * u(rng);
    for (std::size_t k = 0; k < m.rest_stride(); ++k)
      m.color_rest[i * m.rest_stride() + k] = 0.05f * u(rng);
  }
  return m;
}

// Two training steps of a 4D model (the SIMD path, colour rows in per-thread blocks) with the
// step fused into the backward equal, bit for bit, the backward followed by Adam::StepGroup; a
// group left out (the opacity, as on an opacity-reset iteration) is not stepped.
TEST(FusedStep, EqualsBackwardThenStep) {
  const Camera camera{PinholeIntrinsics::FromFovX(0.9, 72, 56),
                      LookAtWorldFromCamGl({0.3, -3.0, 0.4}, {0, 0, 0}, Eigen::Vector3d::UnitZ())};
  RenderOptions options;
  options.background = {0.1f, 0.2f, 0.3f};
  // `colour_buffers` false: the trainer's batch-size-1 layout, no colour gradient buffer at all
  // (ColourRowsOnly); the rows reach the step only through the callback.
  auto run = [&](bool fused, bool colour_buffers = true) {
    GaussianModel model = RandomModel(2500, 5);
    GaussianGradients grads;
    grads.ZerosLike(model, colour_buffers);
    EXPECT_EQ(ColourRowsOnly(model, grads), !colour_buffers);
    Adam adam;
    AddModelGroups(model, grads, LearningRatesAt(OptimizationOptions{}, 3.0, 1), &adam);
    std::vector<std::string> groups;
    for (const char* g : kModelGroups) {
      if (std::string(g) != kGroupOpacity) groups.emplace_back(g);
    }
    FrameState state;
    std::vector<float> image(72 * 56 * 3), dL(image.size());
    for (int it = 0; it < 2; ++it) {
      RenderForward(model, camera, 0.5f, options, &state, image.data());
      for (std::size_t i = 0; i < image.size(); ++i) dL[i] = image[i] - 0.4f;
      if (fused) {
        AdamRowStep step = adam.BeginRowStep(groups, model.size());
        RenderBackward(model, camera, 0.5f, options, &state, dL.data(), &grads,
                       StepModelRows(groups, &step));
        EXPECT_EQ(step.FirstNonFinite(), "");
      } else {
        RenderBackward(model, camera, 0.5f, options, &state, dL.data(), &grads);
        for (const std::string& g : groups) adam.StepGroup(g);
      }
    }
    return model;
  };
  const GaussianModel a = run(true), b = run(false), start = RandomModel(2500, 5);
  const GaussianModel rows_only = run(true, /*colour_buffers=*/false);
  EXPECT_TRUE(rows_only.xyz == a.xyz);
  EXPECT_TRUE(rows_only.color_dc == a.color_dc);
  EXPECT_TRUE(rows_only.color_rest == a.color_rest);
  EXPECT_TRUE(a.xyz == b.xyz);
  EXPECT_TRUE(a.t == b.t);
  EXPECT_TRUE(a.log_scales == b.log_scales);
  EXPECT_TRUE(a.rot_left == b.rot_left);
  EXPECT_TRUE(a.rot_right == b.rot_right);
  EXPECT_TRUE(a.color_dc == b.color_dc);
  EXPECT_TRUE(a.color_rest == b.color_rest);
  EXPECT_TRUE(a.opacity_logit == start.opacity_logit);
  EXPECT_FALSE(a.color_rest == start.color_rest);
  EXPECT_FALSE(a.xyz == start.xyz);
}

// A densifying iteration steps no model group, but a NaN in its colour rows must still stop
// training: with no colour gradient buffer (ColourRowsOnly) the rows are checked as they pass.
TEST(FusedStep, DensifyingStepChecksColourRowsItDoesNotStore) {
  GaussianModel model = RandomModel(40, 7);
  const GaussianModel start = model;
  GaussianGradients grads;
  grads.ZerosLike(model, /*colour=*/false);
  ModelOptimizer optimizer(OptimizationOptions{}, 3.0);
  optimizer.AddGroups(model, grads, nullptr);
  std::vector<float> dc(model.color_dc.size(), 0.5f), rest(model.color_rest.size(), 0.25f);
  for (const bool poison : {false, true}) {
    if (poison) rest[7 * model.rest_stride() + 3] = std::nanf("");
    const GradientRowsDone rows =
        optimizer.Begin(/*densify=*/true, /*reset_opacity=*/false, model.size());
    ASSERT_TRUE(static_cast<bool>(rows));
    rows(0, 20, GradientRows{dc.data(), rest.data()});
    rows(20, 40, GradientRows{dc.data() + 20 * 3, rest.data() + 20 * model.rest_stride()});
    EXPECT_EQ(optimizer.FirstNonFinite(), poison ? kGroupFRest : "");
    optimizer.Finish();
  }
  EXPECT_TRUE(model.color_rest == start.color_rest);  // checked, not stepped
  EXPECT_TRUE(model.xyz == start.xyz);
  // The next step starts clean: a verdict belongs to the step that made it.
  optimizer.Begin(/*densify=*/false, /*reset_opacity=*/false, model.size());
  EXPECT_EQ(optimizer.FirstNonFinite(), "");
}

TEST(FusedStep, NoGroupsNoCallback) {
  Adam adam;
  AdamRowStep step = adam.BeginRowStep({}, 10);
  EXPECT_FALSE(static_cast<bool>(StepModelRows({}, &step)));
}

}  // namespace
}  // namespace hdr4d::method
