#include "baselines/durand_tone_mapper.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "baselines/test_util.h"
#include "core/util/parallel.h"

namespace hdr4d::baselines {
namespace {

using namespace testing;  // baselines/test_util.h

method::ToneMapperConfig Config() {
  method::ToneMapperConfig config;
  config.kind = "durand";
  return config;
}

TEST(DurandToneMapper, UsesThe2002FilterAndStartsAtItsInitialParameters) {
  DurandToneMapper mapper(Config());
  ASSERT_EQ(mapper.params().size(), 3u);
  EXPECT_NEAR(std::exp(mapper.params()[0]), 0.5, 1e-6);
  EXPECT_NEAR(std::exp(mapper.params()[1]), 0.18, 1e-6);
  EXPECT_NEAR(std::exp(mapper.params()[2]), 2.2, 1e-6);
  EXPECT_FALSE(mapper.pointwise());
  EXPECT_FLOAT_EQ(mapper.learning_rate(), 0.01f);
  EXPECT_DOUBLE_EQ(DefaultDurandFilter(800, 600).sigma_space, 16.0);
  EXPECT_DOUBLE_EQ(DefaultDurandFilter(20, 10).sigma_space, 1.0);
  EXPECT_NEAR(DefaultDurandFilter(20, 10).sigma_range, 0.4 * std::log(10.0), 1e-12);
}

// A uniform image is its own base layer: log C = x + (compression - 1) l + offset exactly.
TEST(DurandToneMapper, CompressesTheLuminanceOfAUniformImage) {
  const std::vector<double> params = {std::log(0.4), -1.0, std::log(2.0)};
  const int w = 6, h = 5;
  const double rgb[3] = {-1.0, 0.5, 0.2}, log_e = 0.3;
  std::vector<double> log_hdr(3 * w * h), ldr(3 * w * h);
  for (int p = 0; p < w * h; ++p) {
    for (int c = 0; c < 3; ++c) log_hdr[3 * p + c] = rgb[c];
  }
  DurandForward(params.data(), log_e, log_hdr.data(), w, h, DefaultDurandFilter(w, h), ldr.data());
  const double lum =
      std::log(0.2126 * std::exp(rgb[0] + log_e) + 0.7152 * std::exp(rgb[1] + log_e) +
               0.0722 * std::exp(rgb[2] + log_e));
  for (int p = 0; p < w * h; ++p) {
    for (int c = 0; c < 3; ++c) {
      const double log_c = rgb[c] + log_e + (0.4 - 1.0) * lum - 1.0;
      EXPECT_NEAR(ldr[3 * p + c], std::pow(std::min(std::exp(log_c), 1.0), 0.5), 1e-12);
    }
  }
}

// The point of the operator: a large step between regions is compressed by the factor, while
// fine texture within a region (far below the range sigma) keeps its full contrast.
TEST(DurandToneMapper, CompressesLargeStepsAndKeepsFineDetail) {
  const int w = 64, h = 32;
  const double compression = 0.25;
  const std::vector<double> params = {std::log(compression), -12.0, 0.0};  // gamma 1, all < 1
  std::vector<double> log_hdr(3 * w * h), ldr(3 * w * h);
  auto level = [&](int x, int y) {
    return (x >= w / 2 ? 6.0 : 0.0) + ((x + y) % 2 ? 0.1 : -0.1);  // step + checkerboard
  };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int c = 0; c < 3; ++c) log_hdr[3 * (y * w + x) + c] = level(x, y);
    }
  }
  DurandFilter filter;
  filter.sigma_space = 3.0;
  DurandForward(params.data(), 0.0, log_hdr.data(), w, h, filter, ldr.data());
  auto out = [&](int x, int y) { return std::log(ldr[3 * (y * w + x)]); };
  // Across the step (away from the edge): 6 * compression.
  const double step = 0.5 * (out(w - 8, 8) + out(w - 7, 8)) - 0.5 * (out(8, 8) + out(7, 8));
  EXPECT_NEAR(step, 6.0 * compression, 0.05);
  // Checkerboard: still about 0.2 peak to peak (a global curve would give 0.2 * compression).
  EXPECT_NEAR(out(9, 8) - out(8, 8), 0.2, 0.03);
}

TEST(DurandToneMapper, BackwardMatchesFiniteDifferencesWithTheFilterWeightsFrozen) {
  const std::vector<double> params = {std::log(0.45), -0.4, std::log(1.9)};
  const int w = 7, h = 6;
  const double log_e = -0.6;
  DurandFilter filter;
  filter.sigma_space = 1.5;
  const std::vector<double> log_hdr = Uniform(3 * w * h, -3.0, 3.0, 51);
  const std::vector<double> weights = Uniform(3 * w * h, -1.0, 1.0, 52);
  std::vector<double> guide(w * h);
  DurandLogLuminance(log_hdr.data(), log_e, w, h, guide.data());
  std::vector<double> d_log_hdr(3 * w * h), d_params(3, 0.0);
  DurandBackward(params.data(), log_e, log_hdr.data(), w, h, filter, weights.data(),
                 d_log_hdr.data(), d_params.data());
  // The forward with the guide (the filter weights) held at the current log luminance.
  auto loss = [&](const std::vector<double>& p, const std::vector<double>& v) {
    std::vector<double> ldr(3 * w * h);
    DurandForwardGuided(p.data(), log_e, v.data(), w, h, filter, guide.data(), ldr.data());
    return Dot(weights, ldr);
  };
  ExpectFdMatch([&](const std::vector<double>& v) { return loss(params, v); }, log_hdr, d_log_hdr);
  ExpectFdMatch([&](const std::vector<double>& p) { return loss(p, log_hdr); }, params, d_params);
  // The guided forward at its own guide is the forward.
  std::vector<double> a(3 * w * h), b(3 * w * h);
  DurandForward(params.data(), log_e, log_hdr.data(), w, h, filter, a.data());
  DurandForwardGuided(params.data(), log_e, log_hdr.data(), w, h, filter, guide.data(), b.data());
  EXPECT_EQ(a, b);
  // A null input gradient still gives the parameter gradient.
  std::vector<double> d_params_only(3, 0.0);
  DurandBackward(params.data(), log_e, log_hdr.data(), w, h, filter, weights.data(),
                 static_cast<double*>(nullptr), d_params_only.data());
  EXPECT_EQ(d_params_only, d_params);
}

TEST(DurandToneMapper, MonotonicInExposureAndRadiance) {
  DurandToneMapper mapper(Config());
  const int w = 40, h = 30;
  const std::vector<float> log_hdr = Uniform<float>(3 * w * h, -4, 4, 7);
  std::vector<float> previous;
  for (float log_e : {-5.f, -2.f, 0.f, 1.f, 4.f}) {
    mapper.BeginFrame({0, -1, log_e});
    std::vector<float> ldr(3 * w * h);
    mapper.MapImage(log_hdr.data(), w, h, ldr.data());
    for (std::size_t k = 0; !previous.empty() && k < ldr.size(); ++k) {
      EXPECT_GE(ldr[k], previous[k]) << k;
    }
    if (!previous.empty()) {
      EXPECT_NE(ldr, previous);
    }
    previous = ldr;
  }
  // Scaling the whole image's radiance acts like exposure.
  std::vector<float> brighter(log_hdr), a(3 * w * h), b(3 * w * h);
  for (float& v : brighter) v += 2.f;
  mapper.BeginFrame({0, -1, 0.f});
  mapper.MapImage(brighter.data(), w, h, a.data());
  mapper.BeginFrame({0, -1, 2.f});
  mapper.MapImage(log_hdr.data(), w, h, b.data());
  for (std::size_t k = 0; k < a.size(); ++k) EXPECT_NEAR(a[k], b[k], 1e-5);
}

TEST(DurandToneMapper, ExtremeInputsAndParametersStayFiniteInUnitRange) {
  DurandToneMapper mapper(Config());
  const int w = 13, h = 5;  // one row per decade 1e-6 .. 1e6, then infinities
  std::vector<float> log_hdr(3 * w * h);
  const float inf = std::numeric_limits<float>::infinity();
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      float* px = &log_hdr[3 * (y * w + x)];
      const float v = float((x - 6) * std::log(10.0));
      px[0] = v, px[1] = y % 2 ? -v : 0.f, px[2] = v;
      if (y == 4 && x % 3 == 0) px[0] = px[1] = px[2] = -inf;
      if (y == 4 && x % 3 == 1) px[0] = px[1] = px[2] = inf;
    }
  }
  std::vector<float> ldr(log_hdr.size()), d(log_hdr.size()), dL(log_hdr.size(), 1.f);
  const std::vector<std::vector<float>> settings = {
      {std::log(0.5f), std::log(0.18f), std::log(2.2f)},
      {1e3f, 1e3f, 1e3f},
      {-1e3f, -1e3f, -1e3f},
      {20.f, 20.f, -20.f}};
  for (const auto& params : settings) {
    mapper.params() = params;
    for (double exposure : {1e-4, 1e-2, 1.0, 1e3}) {
      mapper.ZeroGrad();
      mapper.BeginFrame({0, -1, float(std::log(exposure))});
      mapper.MapImage(log_hdr.data(), w, h, ldr.data());
      mapper.MapImageBackward(log_hdr.data(), w, h, dL.data(), d.data());
      EXPECT_TRUE(AllFiniteIn01(ldr)) << params[0] << " " << exposure;
      EXPECT_TRUE(AllFinite(d)) << params[0] << " " << exposure;
      EXPECT_TRUE(AllFinite(mapper.grads())) << params[0] << " " << exposure;
      EXPECT_EQ(d[3 * (4 * w)], 0.f);  // log 0: clamped, no gradient
    }
  }
}

TEST(DurandToneMapper, GradientsAreIdenticalAtAnyThreadCount) {
  DurandToneMapper mapper(Config());
  const int w = 160, h = 120;
  const std::vector<float> log_hdr = Uniform<float>(3 * w * h, -5, 5, 1);
  const std::vector<float> dL = Uniform<float>(3 * w * h, -1, 1, 2);
  mapper.BeginFrame({0, -1, 0.5f});
  std::vector<std::vector<float>> grads, d_inputs;
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    mapper.ZeroGrad();
    std::vector<float> d(3 * w * h);
    mapper.MapImageBackward(log_hdr.data(), w, h, dL.data(), d.data());
    grads.push_back(mapper.grads());
    d_inputs.push_back(d);
  }
  EXPECT_NE(grads[0][0], 0.f);
  EXPECT_EQ(std::memcmp(grads[0].data(), grads[1].data(), 3 * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(d_inputs[0].data(), d_inputs[1].data(), d_inputs[0].size() * 4), 0);
}

TEST(DurandToneMapperDeathTest, PointwiseMappingIsACallerBug) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  DurandToneMapper mapper(Config());
  std::vector<float> v(3, 0.f), out(3);
  EXPECT_DEATH(mapper.Map(v.data(), 1, out.data()), "not pointwise");
  EXPECT_DEATH(mapper.MapBackward(v.data(), 1, v.data(), out.data()), "not pointwise");
}

}  // namespace
}  // namespace hdr4d::baselines
