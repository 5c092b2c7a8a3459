// The learned background (method/render/learned_background.h) through a whole render: its
// gradient against central differences for log-HDR colours on 6 channels (through the Dynamic
// Tone Mapper) and 3 (HDR only), and for LDR colours; the mapper's parameters get no share of
// the backdrop's gradient.
#include "method/render/learned_background.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "method/render/frame_render.h"
#include "method/render/hdr_color_stage.h"
#include "method/tonemap/tone_mapper_registry.h"

namespace hdr4d::method {
namespace {

// Three Gaussians in the middle of a 20 x 16 view: most pixels see the backdrop through some
// transmittance, the corners see only the backdrop.
GaussianModel SmallScene(ColorMode mode) {
  GaussianModel m;
  m.color_mode = mode;
  m.temporal = false;
  m.basis.max_time_degree = 0;
  m.Resize(3);
  for (int i = 0; i < 3; ++i) {
    m.xyz[i * 3 + 0] = -0.4f + 0.4f * i;
    m.xyz[i * 3 + 2] = 0.1f * i;
    for (int a = 0; a < 4; ++a) m.log_scales[i * 4 + a] = std::log(0.25f);
    m.rot_left[i * 4] = m.rot_right[i * 4] = 1.0f;
    m.opacity_logit[i] = -0.5f + 0.5f * i;
    for (int c = 0; c < 3; ++c) m.color_dc[i * 3 + c] = 0.3f * (c - 1) + 0.2f * i;
  }
  return m;
}

struct Case {
  ColorMode mode;
  bool map;  // log-HDR: 6 channels through the tone mapper, else 3 HDR channels
};

void CheckBackgroundGradient(const Case& k) {
  const bool log_hdr = k.mode == ColorMode::kLogHdr;
  GaussianModel model = SmallScene(k.mode);
  ToneMapperConfig tc;
  tc.tabulated = false;  // the curve's own MLP: smooth for the differences
  tc.context_window = 2;
  tc.num_times = 2;
  std::unique_ptr<ToneMapper> tm = MakeToneMapper(tc);
  std::optional<HdrColorStage> stage;
  RenderOptions options;
  options.sh_degree = options.time_degree = 0;
  if (log_hdr) {
    stage.emplace(tm.get(), k.map);
    stage->SetFrame({.time_index = 1, .log_exposure = std::log(0.5f)}, false);
    options.color_stage = &*stage;
  }
  const int channels = log_hdr ? stage->feature_channels() : 3;
  LearnedBackground background(log_hdr ? std::vector<float>{-1.0f, 0.3f, -2.0f}
                                       : std::vector<float>{0.2f, 0.5f, 0.7f},
                               log_hdr, tm.get());
  options.background_source = &background;
  const Camera camera{PinholeIntrinsics::FromFovX(0.9, 20, 16),
                      LookAtWorldFromCamGl({0, -4, 0.2}, {0, 0, 0}, Eigen::Vector3d::UnitZ())};
  const std::size_t values = 20 * 16 * std::size_t(channels);
  std::mt19937 rng(7);
  std::vector<float> w(values);
  for (float& x : w) x = std::uniform_real_distribution<float>(0.2f, 1.0f)(rng);  // one sign: no cancelling
  FrameState state;
  std::vector<float> image(values);
  auto loss = [&] {
    RenderForward(model, camera, 0.5f, options, &state, image.data());
    double l = 0;
    for (std::size_t i = 0; i < values; ++i) l += double(w[i]) * image[i];
    return l;
  };
  loss();
  ASSERT_EQ(state.background.size(), std::size_t(channels));
  // A corner pixel sees nothing but the backdrop.
  for (int c = 0; c < channels; ++c) EXPECT_FLOAT_EQ(image[c], state.background[c]);
  GaussianGradients grads;
  grads.ZerosLike(model);
  background.ZeroGrad();
  tm->ZeroGrad();
  RenderBackward(model, camera, 0.5f, options, &state, w.data(), &grads);
  tm->EndFrameBackward();
  const std::vector<float> analytic = background.grads();
  if (log_hdr && k.map) {
    // The backdrop gives the curves no gradient: theirs equals that of a render over a fixed
    // background of the same values.
    const std::vector<float> with_learned = tm->grads();
    RenderOptions fixed = options;
    fixed.background_source = nullptr;
    fixed.background = state.background;
    FrameState fixed_state;
    std::vector<float> fixed_image(values);
    RenderForward(model, camera, 0.5f, fixed, &fixed_state, fixed_image.data());
    EXPECT_EQ(fixed_image, image);
    GaussianGradients fixed_grads;
    fixed_grads.ZerosLike(model);
    tm->ZeroGrad();
    RenderBackward(model, camera, 0.5f, fixed, &fixed_state, w.data(), &fixed_grads);
    tm->EndFrameBackward();
    EXPECT_EQ(tm->grads(), with_learned);
    double mapper = 0;
    for (float g : with_learned) mapper += std::abs(g);
    EXPECT_GT(mapper, 0.0);  // the Gaussians' share is there
  }
  const float h = 1e-2f;
  for (int c = 0; c < 3; ++c) {
    const float b0 = background.params()[c];
    background.params()[c] = b0 + h;
    const double plus = loss();
    background.params()[c] = b0 - h;
    const double minus = loss();
    background.params()[c] = b0;
    const double numeric = (plus - minus) / (2 * h);
    EXPECT_NEAR(analytic[c], numeric, 1e-2 * std::abs(numeric) + 1e-3) << "channel " << c;
    EXPECT_GT(std::abs(numeric), 1.0);  // the backdrop is in most pixels: a real check
  }
}

TEST(LearnedBackground, LogHdrThroughTheToneMapperMatchesCentralDifferences) {
  CheckBackgroundGradient({ColorMode::kLogHdr, true});
}

TEST(LearnedBackground, LogHdrWithoutMappingMatchesCentralDifferences) {
  CheckBackgroundGradient({ColorMode::kLogHdr, false});
}

TEST(LearnedBackground, LdrColourMatchesCentralDifferences) {
  CheckBackgroundGradient({ColorMode::kLdr, false});
}

// Radiance far beyond the guard: finite forward values and no gradient past e^30, as for a
// Gaussian's colour.
TEST(LearnedBackground, ExtremeLogRadianceStaysFinite) {
  LearnedBackground background({80.0f, -80.0f, 0.0f}, true, nullptr);
  std::vector<float> out;
  background.Forward(3, &out);
  for (float v : out) EXPECT_TRUE(std::isfinite(v));
  EXPECT_FLOAT_EQ(out[0], std::exp(kMaxLogRadiance));
  const float d[3] = {1, 1, 1};
  background.Backward(3, d);
  EXPECT_EQ(background.grads()[0], 0.0f);
  EXPECT_TRUE(std::isfinite(background.grads()[1]));
}

// A render that wants the tone-mapped image alone (HdrColorStage::SetLdrOnly and the background's
// SetLdrOnly) blends 3 channels that hold exactly what channels 3-5 of the full render hold,
// backdrop included; switched back, the full render is what it was.
TEST(LearnedBackground, ToneMappedAloneIsChannelsThreeToFiveOfTheFullRender) {
  GaussianModel model = SmallScene(ColorMode::kLogHdr);
  ToneMapperConfig tc;
  tc.context_window = 2;
  tc.num_times = 2;
  std::unique_ptr<ToneMapper> tm = MakeToneMapper(tc);
  HdrColorStage stage(tm.get(), true);
  stage.SetFrame({.time_index = 1, .log_exposure = std::log(0.5f)}, false);
  LearnedBackground background({-1.0f, 0.3f, -2.0f}, true, tm.get());
  RenderOptions options;
  options.sh_degree = options.time_degree = 0;
  options.color_stage = &stage;
  options.background_source = &background;
  options.backward_follows = false;
  const Camera camera{PinholeIntrinsics::FromFovX(0.9, 20, 16),
                      LookAtWorldFromCamGl({0, -4, 0.2}, {0, 0, 0}, Eigen::Vector3d::UnitZ())};
  const std::size_t pixels = 20 * 16;
  FrameState state;
  std::vector<float> full(pixels * 6), alone(pixels * 3), again(pixels * 6);
  ASSERT_EQ(stage.feature_channels(), 6);
  RenderForward(model, camera, 0.5f, options, &state, full.data());
  stage.SetLdrOnly(true);
  background.SetLdrOnly(true);
  ASSERT_EQ(stage.feature_channels(), 3);
  RenderForward(model, camera, 0.5f, options, &state, alone.data());
  double tone_mapped = 0;
  for (std::size_t p = 0; p < pixels; ++p) {
    for (int c = 0; c < 3; ++c) {
      ASSERT_EQ(alone[p * 3 + c], full[p * 6 + 3 + c]) << "pixel " << p << " channel " << c;
      tone_mapped += alone[p * 3 + c];
    }
  }
  EXPECT_GT(tone_mapped, 0.0);
  stage.SetLdrOnly(false);
  background.SetLdrOnly(false);
  RenderForward(model, camera, 0.5f, options, &state, again.data());
  EXPECT_EQ(again, full);
}

}  // namespace
}  // namespace hdr4d::method
