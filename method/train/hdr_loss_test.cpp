// The HDR pieces of the training loss and the 3D branch: mu-law, the pixel log, the guarded exp
// (finite differences in double), then the whole view loss and the colour stage, whose float
// gradients are checked along random directions against central differences.
#include "method/train/hdr_loss.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>

#include "core/geometry/camera.h"
#include "method/render/frame_render.h"
#include "method/render/hdr_color_stage.h"
#include "tests/finite_difference.h"

namespace hdr4d::method {
namespace {

using testing::ExpectGradientsMatch;
using testing::FdVector;
using testing::NumericGradient;

// A small learnable pointwise tone mapper for the tests: ldr = sigmoid(a (x + log e) + b).
class AffineSigmoid final : public ToneMapper {
 public:
  AffineSigmoid() : params_{0.7f, -0.2f}, grads_(2, 0.f) {}
  const ToneMapperConfig& config() const override { return config_; }
  bool pointwise() const override { return true; }
  void BeginFrame(const ToneFrame& frame) override {
    frame_ = frame;
    ++frames_begun;
  }
  void Map(const float* x, std::size_t n, float* ldr) const override {
    for (std::size_t i = 0; i < 3 * n; ++i) ldr[i] = Eval(x[i]);
  }
  void MapBackward(const float* x, std::size_t n, const float* g, float* dx) override {
    for (std::size_t i = 0; i < 3 * n; ++i) {
      const float y = Eval(x[i]);
      const float dz = g[i] * y * (1 - y);
      if (dx) dx[i] = dz * params_[0];
      grads_[0] += dz * (x[i] + frame_.log_exposure);
      grads_[1] += dz;
    }
  }
  void ObserveMeanLogHdr(int time_index, const float* mean) override {
    observed_index = time_index;
    for (int c = 0; c < 3; ++c) observed[c] = mean[c];
  }
  std::vector<float>& params() override { return params_; }
  std::vector<float>& grads() override { return grads_; }
  void Save(std::ostream&) const override {}
  void Load(std::istream&, const std::string&) override {}

  int frames_begun = 0, observed_index = -1;
  float observed[3] = {0, 0, 0};

 private:
  float Eval(float x) const {
    return 1.0f / (1.0f + std::exp(-(params_[0] * (x + frame_.log_exposure) + params_[1])));
  }
  ToneMapperConfig config_;
  ToneFrame frame_;
  std::vector<float> params_, grads_;
};

TEST(HdrLoss, ScalarPiecesMatchFiniteDifferences) {
  for (double x : {1e-6, 1e-3, 0.2, 1.0, 7.5, 1e3}) {
    FdVector at(1);
    at << x;
    FdVector analytic(1);
    analytic << MuLawEncodeBackward(x, 1.0);
    ExpectGradientsMatch(
        analytic,
        NumericGradient([](const FdVector& v) { return MuLawEncode(v(0)); }, at, x * 1e-4), 1e-6);
    for (double eps : {1e-5, 1e-8}) {
      analytic << PixelLogBackward(x, 1.0, eps);
      ExpectGradientsMatch(
          analytic,
          NumericGradient([eps](const FdVector& v) { return PixelLog(v(0), eps); }, at, x * 1e-4),
          1e-6);
    }
  }
  for (double c : {-20.0, -1.0, 0.0, 3.0, 13.8, 29.0}) {
    FdVector at(1);
    at << c;
    FdVector analytic(1);
    analytic << GuardedExpBackward(c, 1.0);
    ExpectGradientsMatch(
        analytic, NumericGradient([](const FdVector& v) { return GuardedExp(v(0)); }, at, 1e-5),
        1e-6);
  }
}

// The coder works log(1 + mu) out once; its floats must stay those of the per-value formulas the
// reference computed (log(1 + mu) in every call), bit for bit, or --reference would drift.
TEST(HdrLoss, MuLawCoderIsThePerValueFormulaBitForBit) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> log_x(-12.0f, 6.0f), g(-2.0f, 2.0f);
  for (const double mu : {5000.0, 1000.0, 50.0}) {
    const MuLawCoder<float> coder(mu);
    for (int i = 0; i < 20000; ++i) {
      const float x = i == 0 ? 0.0f : i == 1 ? -1e-7f : std::pow(10.0f, log_x(rng));
      const float d = g(rng);
      const float y = x > 0.0f ? x : 0.0f;
      const float encode = std::log1p(float(mu) * y) / std::log(1.0f + float(mu));
      const float backward =
          x > 0.0f ? d * float(mu) / ((1.0f + float(mu) * x) * std::log(1.0f + float(mu))) : 0.0f;
      ASSERT_EQ(coder.Encode(x), encode) << "x " << x << " mu " << mu;
      ASSERT_EQ(coder.EncodeBackward(x, d), backward) << "x " << x << " mu " << mu;
    }
  }
}

TEST(HdrLoss, GuardsKeepEverythingFinite) {
  EXPECT_EQ(MuLawEncode(0.0), 0.0);
  EXPECT_NEAR(MuLawEncode(1.0), 1.0, 1e-12);
  EXPECT_EQ(MuLawEncode(-1.0), 0.0);
  EXPECT_EQ(MuLawEncodeBackward(-1.0, 1.0), 0.0);
  EXPECT_TRUE(std::isfinite(MuLawEncode(1e30f)));
  for (double x : {1e-9, 1e-4, 0.3, 1.0})  // the inverse, at both targets' mu
    for (double mu : {5000.0, 1e6}) EXPECT_NEAR(MuLawDecode(MuLawEncode(x, mu), mu), x, 1e-12 * mu);
  for (float eps : {kReferencePixelLogEpsilon, kHdrUnitsPixelLogEpsilon}) {
    EXPECT_NEAR(PixelLog(0.0f, eps), std::log(eps), 1e-5);  // log of 0 is guarded
    EXPECT_TRUE(std::isfinite(PixelLog(-5.0f, eps)));
    EXPECT_EQ(PixelLogBackward(0.0f, 1.0f, eps), 0.0f);
    EXPECT_TRUE(std::isfinite(PixelLogBackward(1e-30f, 1.0f, eps)));
  }
  EXPECT_TRUE(std::isfinite(GuardedExp(1e6f)));
  EXPECT_EQ(GuardedExp(1e6f), GuardedExp(kMaxLogRadiance));
  EXPECT_EQ(GuardedExpBackward(31.0f, 1.0f), 0.0f);
}

struct LossCase {
  int w = 12, h = 10;
  std::vector<float> raster, ldr_gt, hdr_mu;
};

LossCase MakeCase(int channels, unsigned seed) {
  LossCase c;
  std::mt19937 rng(seed);
  auto u = [&](float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(rng); };
  const std::size_t pixels = std::size_t(c.w) * c.h;
  c.raster.resize(pixels * channels);
  for (std::size_t p = 0; p < pixels; ++p) {
    for (int k = 0; k < 3; ++k) c.raster[p * channels + k] = u(0.01f, 3.0f);          // HDR
    for (int k = 3; k < channels; ++k) c.raster[p * channels + k] = u(0.05f, 0.95f);  // LDR
  }
  c.ldr_gt.resize(pixels * 3);
  c.hdr_mu.resize(pixels * 3);
  for (float& v : c.ldr_gt) v = u(0, 1);
  for (float& v : c.hdr_mu) v = u(0, 1);
  return c;
}

// Checks dL/draster along random directions: (L(r + h v) - L(r - h v)) / 2h = grad . v.
void ExpectDirectionalDerivatives(LossCase& c,
                                  int channels,
                                  const SupervisionTerms& terms,
                                  bool with_hdr) {
  AffineSigmoid tm;
  tm.BeginFrame({.time_index = 0, .log_exposure = std::log(0.5f)});
  HdrLossScratch scratch;
  std::vector<float> grad(c.raster.size()), unused(c.raster.size());
  const float* mu = with_hdr ? c.hdr_mu.data() : nullptr;
  HdrFrameLoss(c.raster.data(), channels, c.w, c.h, c.ldr_gt.data(), mu, &tm, terms, &scratch,
               grad.data());
  std::mt19937 rng(5);
  for (int trial = 0; trial < 3; ++trial) {
    std::vector<float> v(c.raster.size());
    double predicted = 0;
    for (std::size_t i = 0; i < v.size(); ++i) {
      v[i] = std::uniform_real_distribution<float>(-1, 1)(rng);
      predicted += double(grad[i]) * v[i];
    }
    const float h = 2e-3f;
    auto loss_at = [&](float s) {
      std::vector<float> r = c.raster;
      for (std::size_t i = 0; i < r.size(); ++i) r[i] += s * v[i];
      return HdrFrameLoss(r.data(), channels, c.w, c.h, c.ldr_gt.data(), mu, &tm, terms, &scratch,
                          unused.data())
          .total;
    };
    const double numeric = (loss_at(h) - loss_at(-h)) / (2 * h);
    EXPECT_NEAR(predicted, numeric, 2e-2 * std::abs(numeric) + 1e-5) << "trial " << trial;
    EXPECT_GT(std::abs(numeric), 1e-4);  // a direction that actually changes the loss
  }
}

// HDR-4DGS with the Dynamic Tone Mapper under `supervision`, before resolving against a scene.
HdrTrainingOptions Hdr4dgsOptions(Supervision supervision) {
  HdrTrainingOptions o;
  o.method = "hdr4dgs";
  o.color_mode = ColorMode::kLogHdr;
  o.tone_mapper = ToneMapperConfig{};
  o.supervision = supervision;
  return o;
}

// Which floor the 2D branch's log takes: the reference's under LDR supervision alone, a lower
// one when an HDR term fixes the raster to the target's units, an explicit value always, and
// the reference's for a run saved before the setting existed (so it renders as it trained).
TEST(HdrLoss, PixelLogEpsilonFollowsTheSupervision) {
  HdrTrainingOptions o = Hdr4dgsOptions(Supervision::kLdr);
  EXPECT_EQ(ResolveHdrTraining(o, true, true).pixel_log_epsilon, kReferencePixelLogEpsilon);
  o.supervision = Supervision::kLdrHdr;
  EXPECT_EQ(ResolveHdrTraining(o, true, true).pixel_log_epsilon, kHdrUnitsPixelLogEpsilon);
  o.supervision = Supervision::kAuto;  // auto: LDR+HDR where the views have HDR truth
  EXPECT_EQ(ResolveHdrTraining(o, true, true).pixel_log_epsilon, kHdrUnitsPixelLogEpsilon);
  EXPECT_EQ(ResolveHdrTraining(o, false, true).pixel_log_epsilon, kReferencePixelLogEpsilon);
  o.pixel_log_epsilon = 1e-6f;
  EXPECT_EQ(ResolveHdrTraining(o, true, true).pixel_log_epsilon, 1e-6f);
  EXPECT_EQ(HdrTrainingOptions::FromJson(o.ToJson(), "x").pixel_log_epsilon, 1e-6f);
  o.pixel_log_epsilon.reset();
  EXPECT_FALSE(HdrTrainingOptions::FromJson(o.ToJson(), "x").pixel_log_epsilon.has_value());
  nlohmann::json old = o.ToJson();
  old.erase("pixel_log_epsilon");
  EXPECT_EQ(HdrTrainingOptions::FromJson(old, "x").pixel_log_epsilon, kReferencePixelLogEpsilon);
  o.pixel_log_epsilon = 0.0f;
  EXPECT_NE(o.Validate(), "");
  o.pixel_log_epsilon = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(o.Validate(), "");
}

TEST(HdrLoss, SixChannelGradientMatchesDirectionalDifferences) {
  LossCase c = MakeCase(6, 3);
  ExpectDirectionalDerivatives(c, 6, SupervisionTerms{}, true);
}

TEST(HdrLoss, EachTermOnItsOwn) {
  LossCase c = MakeCase(6, 4);
  ExpectDirectionalDerivatives(c, 6, {.ldr_gaussian = true, .ldr_pixel = false, .hdr = false},
                               true);
  ExpectDirectionalDerivatives(c, 6, {.ldr_gaussian = false, .ldr_pixel = true, .hdr = false},
                               true);
  ExpectDirectionalDerivatives(c, 6, {.ldr_gaussian = false, .ldr_pixel = false, .hdr = true},
                               true);
  LossCase hdr_only = MakeCase(3, 6);
  ExpectDirectionalDerivatives(hdr_only, 3,
                               {.ldr_gaussian = false, .ldr_pixel = false, .hdr = true}, true);
}

TEST(HdrLoss, HdrTermNeedsGroundTruthAndTermsAddUp) {
  LossCase c = MakeCase(6, 8);
  AffineSigmoid tm;
  tm.BeginFrame({});
  HdrLossScratch scratch;
  std::vector<float> grad(c.raster.size());
  const FrameLoss without = HdrFrameLoss(c.raster.data(), 6, c.w, c.h, c.ldr_gt.data(), nullptr,
                                         &tm, SupervisionTerms{}, &scratch, grad.data());
  EXPECT_EQ(without.hdr, 0.0);
  const FrameLoss with =
      HdrFrameLoss(c.raster.data(), 6, c.w, c.h, c.ldr_gt.data(), c.hdr_mu.data(), &tm,
                   SupervisionTerms{}, &scratch, grad.data());
  EXPECT_GT(with.hdr, 0.0);
  EXPECT_NEAR(with.total, with.ldr_gaussian + with.ldr_pixel + 0.6 * with.hdr, 1e-6);
  EXPECT_DOUBLE_EQ(with.ldr_gaussian, without.ldr_gaussian);
  // A perfect prediction of the mu-law target has zero HDR loss.
  std::vector<float> mu(c.w * c.h * 3);
  for (std::size_t p = 0; p < mu.size() / 3; ++p)
    for (int k = 0; k < 3; ++k) mu[p * 3 + k] = MuLawEncode(c.raster[p * 6 + k]);
  const FrameLoss perfect =
      HdrFrameLoss(c.raster.data(), 6, c.w, c.h, c.ldr_gt.data(), mu.data(), &tm,
                   {.ldr_gaussian = false, .ldr_pixel = false}, &scratch, grad.data());
  EXPECT_NEAR(perfect.hdr, 0.0, 1e-6);
}

// --hdr-target aligned: the median ratio recovers one global factor between render and target,
// after which the term sees a perfect render; a target the encoding cannot resolve (or a render
// with nothing in it) leaves the factor at 1.
TEST(HdrLoss, AlignScaleRecoversAGlobalFactorAndTheTermIgnoresIt) {
  LossCase c = MakeCase(3, 9);
  const std::size_t values = c.hdr_mu.size();
  std::vector<float> render(values);
  for (std::size_t i = 0; i < values; ++i) render[i] = MuLawDecode(c.hdr_mu[i], kMuLawMu) / 40.0f;
  render[7] = std::numeric_limits<float>::quiet_NaN();  // skipped, not propagated
  std::vector<double> ratios;
  EXPECT_NEAR(HdrAlignScale(render, c.hdr_mu.data(), kMuLawMu, &ratios), 40.0, 40.0 * 1e-4);
  render[7] = render[8];
  AffineSigmoid tm;
  tm.BeginFrame({});
  HdrLossScratch scratch;
  std::vector<float> grad(values);
  const SupervisionTerms hdr_only{.ldr_gaussian = false, .ldr_pixel = false};
  SupervisionTerms aligned = hdr_only;
  aligned.hdr_align = true;
  std::vector<float> truth = render;
  for (float& v : truth) v *= 40.0f;
  std::vector<float> mu(values);
  for (std::size_t i = 0; i < values; ++i) mu[i] = MuLawEncode(truth[i]);
  const FrameLoss plain = HdrFrameLoss(render.data(), 3, c.w, c.h, c.ldr_gt.data(), mu.data(),
                                       &tm, hdr_only, &scratch, grad.data());
  const FrameLoss fitted = HdrFrameLoss(render.data(), 3, c.w, c.h, c.ldr_gt.data(), mu.data(),
                                        &tm, aligned, &scratch, grad.data());
  EXPECT_GT(plain.hdr, 0.1);
  EXPECT_EQ(plain.hdr_scale, 1.0);
  EXPECT_NEAR(fitted.hdr_scale, 40.0, 40.0 * 1e-4);
  EXPECT_NEAR(fitted.hdr, 0.0, 1e-4);
  std::vector<float> dark(values, MuLawEncode(0.5f / kMuLawMu));
  EXPECT_EQ(HdrAlignScale(render, dark.data(), kMuLawMu, &ratios), 1.0);
  EXPECT_EQ(HdrAlignScale(std::vector<float>(values, 0.0f), mu.data(), kMuLawMu, &ratios), 1.0);
  // Extreme factors are clamped, not overflowed.
  std::vector<float> tiny(values, 1e-30f);
  EXPECT_TRUE(std::isfinite(HdrAlignScale(tiny, mu.data(), kMuLawMu, &ratios)));
}

// The aligned term's gradient with the view's factor held constant (the stop-gradient the
// trainer applies), along random directions.
TEST(HdrLoss, AlignedTermGradientAtAFixedScaleMatchesDirectionalDifferences) {
  LossCase c = MakeCase(3, 10);
  std::vector<float> hdr = c.raster;
  for (float& v : hdr) v *= 0.01f;
  const SupervisionTerms terms{.ldr_gaussian = false, .ldr_pixel = false, .hdr_weight = 0.6f};
  const double scale = 37.5;
  HdrLossScratch scratch;
  std::vector<float> grad(hdr.size(), 0.0f), unused(hdr.size());
  AddHdrTerm(hdr, c.hdr_mu.data(), c.w, c.h, 3, terms, scale, &scratch, grad.data());
  std::mt19937 rng(11);
  for (int trial = 0; trial < 3; ++trial) {
    std::vector<float> v(hdr.size());
    double predicted = 0;
    for (std::size_t i = 0; i < v.size(); ++i) {
      v[i] = std::uniform_real_distribution<float>(-1, 1)(rng) * hdr[i];  // relative steps
      predicted += double(grad[i]) * v[i];
    }
    auto loss_at = [&](float h) {
      std::vector<float> r = hdr;
      for (std::size_t i = 0; i < r.size(); ++i) r[i] += h * v[i];
      return 0.6 * AddHdrTerm(r, c.hdr_mu.data(), c.w, c.h, 3, terms, scale, &scratch,
                              unused.data());
    };
    const float h = 2e-2f;
    const double numeric = (loss_at(h) - loss_at(-h)) / (2 * h);
    EXPECT_NEAR(predicted, numeric, 2e-2 * std::abs(numeric) + 1e-5) << "trial " << trial;
    EXPECT_GT(std::abs(numeric), 1e-4);
  }
}

// --no-hdr-geometry: the loss and its dL/draster are those of the full loss; the geometry buffer
// holds dL/draster of the LDR terms alone, and is written only when the HDR term runs.
TEST(HdrLoss, WithoutHdrGeometryTheGeometryBufferHoldsTheLdrTermsAlone) {
  LossCase c = MakeCase(6, 9);
  AffineSigmoid tm;
  tm.BeginFrame({.time_index = 0, .log_exposure = 0.3f});
  HdrLossScratch scratch;
  const std::size_t n = c.raster.size();
  const SupervisionTerms full{};
  SupervisionTerms split = full;
  split.hdr_geometry = false;
  SupervisionTerms ldr_only = full;
  ldr_only.hdr = false;
  std::vector<float> g_full(n), g_split(n), g_ldr(n), geometry(n, -9.0f);
  const FrameLoss a = HdrFrameLoss(c.raster.data(), 6, c.w, c.h, c.ldr_gt.data(), c.hdr_mu.data(),
                                   &tm, full, &scratch, g_full.data(), geometry.data());
  EXPECT_FALSE(a.geometry_split);  // the HDR term reaches the geometry: nothing written
  EXPECT_EQ(geometry, std::vector<float>(n, -9.0f));
  const FrameLoss b = HdrFrameLoss(c.raster.data(), 6, c.w, c.h, c.ldr_gt.data(), c.hdr_mu.data(),
                                   &tm, split, &scratch, g_split.data(), geometry.data());
  HdrFrameLoss(c.raster.data(), 6, c.w, c.h, c.ldr_gt.data(), c.hdr_mu.data(), &tm, ldr_only,
               &scratch, g_ldr.data());
  EXPECT_TRUE(b.geometry_split);
  EXPECT_EQ(a.total, b.total);
  EXPECT_GT(b.hdr, 0.0);
  EXPECT_EQ(g_split, g_full);
  EXPECT_EQ(geometry, g_ldr);
  EXPECT_NE(geometry, g_full);  // the HDR term moved channels 0-2
  // A view without HDR truth has no HDR term to keep off the geometry.
  std::vector<float> untouched(n, -9.0f);
  const FrameLoss d = HdrFrameLoss(c.raster.data(), 6, c.w, c.h, c.ldr_gt.data(), nullptr, &tm,
                                   split, &scratch, g_split.data(), untouched.data());
  EXPECT_FALSE(d.geometry_split);
  EXPECT_EQ(untouched, std::vector<float>(n, -9.0f));
}

TEST(HdrLoss, ToneMapperParametersReceiveTheirGradient) {
  LossCase c = MakeCase(6, 9);
  AffineSigmoid tm;
  const ToneFrame frame{.time_index = 0, .log_exposure = 0.3f};
  tm.BeginFrame(frame);
  HdrLossScratch scratch;
  std::vector<float> grad(c.raster.size());
  const SupervisionTerms pixel_only{.ldr_gaussian = false, .ldr_pixel = true, .hdr = false};
  tm.ZeroGrad();
  HdrFrameLoss(c.raster.data(), 6, c.w, c.h, c.ldr_gt.data(), nullptr, &tm, pixel_only, &scratch,
               grad.data());
  const float analytic = tm.grads()[0];
  const float h = 1e-2f;
  auto at = [&](float a) {
    tm.params()[0] = a;
    return HdrFrameLoss(c.raster.data(), 6, c.w, c.h, c.ldr_gt.data(), nullptr, &tm, pixel_only,
                        &scratch, grad.data())
        .total;
  };
  const float a0 = tm.params()[0];
  const double numeric = (at(a0 + h) - at(a0 - h)) / (2 * h);
  EXPECT_NEAR(analytic, numeric, 2e-2 * std::abs(numeric) + 1e-6);
}

TEST(HdrColorStage, WritesExpAndToneMappedColoursOfVisibleRowsAndTheBank) {
  AffineSigmoid tm;
  HdrColorStage stage(&tm, true);
  stage.SetFrame({.time_index = 2, .log_exposure = 0.4f}, true);
  ASSERT_EQ(stage.feature_channels(), 6);
  const std::vector<float> colors = {0.1f, -0.5f, 2.0f, 9, 9, 9, -3.0f, 0.0f, 1.0f};
  const std::vector<std::uint32_t> visible = {0, 2};
  std::vector<float> features(18, -7.0f);
  stage.Forward(colors.data(), 3, visible, features.data());
  for (std::uint32_t i : visible) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_FLOAT_EQ(features[i * 6 + c], std::exp(colors[i * 3 + c]));
      EXPECT_FLOAT_EQ(features[i * 6 + 3 + c],
                      1 / (1 + std::exp(-(0.7f * (colors[i * 3 + c] + 0.4f) - 0.2f))));
    }
  }
  for (int k = 0; k < 6; ++k) EXPECT_EQ(features[6 + k], -7.0f);  // a culled row is untouched
  EXPECT_EQ(tm.observed_index, 2);
  EXPECT_FLOAT_EQ(tm.observed[0], (0.1f - 3.0f) / 2);  // mean over the visible rows only
  EXPECT_EQ(tm.frames_begun, 1);

  HdrColorStage hdr_only(&tm, false);
  EXPECT_EQ(hdr_only.feature_channels(), 3);
  HdrColorStage no_mapper(nullptr, true);
  EXPECT_EQ(no_mapper.feature_channels(), 3);
}

TEST(HdrColorStage, BackwardMatchesDirectionalDifferences) {
  AffineSigmoid tm;
  HdrColorStage stage(&tm, true);
  stage.SetFrame({.time_index = 0, .log_exposure = -1.0f}, false);
  std::mt19937 rng(2);
  auto u = [&](float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(rng); };
  const int n = 50;
  std::vector<float> colors(n * 3), w(n * 6), v(n * 3);
  for (float& x : colors) x = u(-2, 2);
  for (float& x : w) x = u(-1, 1);
  for (float& x : v) x = u(-1, 1);
  std::vector<std::uint32_t> visible;
  for (int i = 0; i < n; i += 2) visible.push_back(i);
  std::vector<float> features(n * 6, 0.0f), dcolors(n * 3, 0.0f);
  auto loss = [&](float s) {
    std::vector<float> c = colors;
    for (int i = 0; i < n * 3; ++i) c[i] += s * v[i];
    stage.Forward(c.data(), 3, visible, features.data());
    double l = 0;
    for (std::uint32_t i : visible)
      for (int k = 0; k < 6; ++k) l += double(w[i * 6 + k]) * features[i * 6 + k];
    return l;
  };
  loss(0);
  tm.ZeroGrad();
  stage.Backward(colors.data(), 3, visible, w.data(), dcolors.data());
  double predicted = 0;
  for (std::uint32_t i : visible)
    for (int k = 0; k < 3; ++k) predicted += double(dcolors[i * 3 + k]) * v[i * 3 + k];
  const float h = 1e-3f;
  const double numeric = (loss(h) - loss(-h)) / (2 * h);
  EXPECT_NEAR(predicted, numeric, 1e-2 * std::abs(numeric));
  EXPECT_NE(tm.grads()[0], 0.0f);  // the mapper's parameters got their share
}

TEST(HdrColorStage, RenderBlendsSixChannelsInOnePass) {
  GaussianModel model;
  model.color_mode = ColorMode::kLogHdr;
  model.Resize(1);
  model.xyz = {0, 0, 0};
  model.t = {0.5f};
  for (int a = 0; a < 4; ++a) model.log_scales[a] = std::log(0.3f);
  model.opacity_logit = {8.0f};  // nearly opaque
  model.color_dc = {0.0f, 1.0f, -1.0f};
  AffineSigmoid tm;
  HdrColorStage stage(&tm, true);
  stage.SetFrame({.time_index = 0, .log_exposure = 0.0f}, true);
  RenderOptions options;
  options.sh_degree = 0;
  options.time_degree = 0;
  options.color_stage = &stage;
  const Camera camera{PinholeIntrinsics::FromFovX(0.8, 16, 16),
                      LookAtWorldFromCamGl({0, -4, 0}, {0, 0, 0}, Eigen::Vector3d::UnitZ())};
  FrameState state;
  std::vector<float> image(16 * 16 * 6);
  RenderForward(model, camera, 0.5f, options, &state, image.data());
  const float* centre = &image[(8 * 16 + 8) * 6];
  // Colour = SH DC weight x coefficient + 0.5. One Gaussian on a black background: every
  // channel is the same blending weight times that channel's feature.
  auto log_hdr = [](float dc) { return 0.28209479f * dc + 0.5f; };
  auto ldr = [](float c) { return 1 / (1 + std::exp(-(0.7f * c - 0.2f))); };
  const float weight = centre[0] / std::exp(log_hdr(0.0f));
  EXPECT_GT(weight, 0.5f);
  EXPECT_NEAR(centre[1], weight * std::exp(log_hdr(1.0f)), 1e-4f);
  EXPECT_NEAR(centre[2], weight * std::exp(log_hdr(-1.0f)), 1e-4f);
  EXPECT_NEAR(centre[3], weight * ldr(log_hdr(0.0f)), 1e-4f);
  EXPECT_NEAR(centre[4], weight * ldr(log_hdr(1.0f)), 1e-4f);
  EXPECT_NEAR(centre[5], weight * ldr(log_hdr(-1.0f)), 1e-4f);
  // Backward reaches the colour coefficients through the stage.
  std::vector<float> dL(image.size(), 0.0f);
  for (std::size_t p = 0; p < 256; ++p) dL[p * 6 + 3] = 1.0f;  // d(sum of LDR red)
  GaussianGradients grads;
  grads.ZerosLike(model);
  tm.ZeroGrad();
  RenderBackward(model, camera, 0.5f, options, &state, dL.data(), &grads);
  EXPECT_GT(grads.color_dc[0], 0.0f);
  EXPECT_EQ(grads.color_dc[1], 0.0f);
  EXPECT_NE(tm.grads()[1], 0.0f);
}

}  // namespace
}  // namespace hdr4d::method
