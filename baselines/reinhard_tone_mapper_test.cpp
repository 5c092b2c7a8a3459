#include "baselines/reinhard_tone_mapper.h"

#include <gtest/gtest.h>

#include <algorithm>
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
  config.kind = "reinhard";
  return config;
}

// The operator as the 2002 paper writes it, in linear radiance.
void Textbook(const double* params, double log_e, const double* log_hdr, double* ldr) {
  const double key = std::exp(params[0]), white = std::exp(params[1]);
  const double gamma = std::exp(params[2]);
  double e[3];
  for (int c = 0; c < 3; ++c) e[c] = std::exp(log_hdr[c] + log_e);
  const double lw = 0.2126 * e[0] + 0.7152 * e[1] + 0.0722 * e[2];
  const double ls = key * lw;
  const double ld = ls * (1 + ls / (white * white)) / (1 + ls);
  for (int c = 0; c < 3; ++c) ldr[c] = std::pow(std::min(ld * e[c] / lw, 1.0), 1 / gamma);
}

TEST(ReinhardToneMapper, StartsAtTheNormalKeyWithADisplayGamma) {
  ReinhardToneMapper mapper(Config());
  ASSERT_EQ(mapper.params().size(), 3u);
  EXPECT_NEAR(std::exp(mapper.params()[0]), 0.18, 1e-6);
  EXPECT_NEAR(std::exp(mapper.params()[1]), 2.0, 1e-6);
  EXPECT_NEAR(std::exp(mapper.params()[2]), 2.2, 1e-6);
  EXPECT_TRUE(mapper.pointwise());
  EXPECT_FLOAT_EQ(mapper.learning_rate(), 0.01f);
}

TEST(ReinhardToneMapper, MatchesThePapersOperator) {
  const std::vector<double> params = {std::log(0.3), std::log(1.7), std::log(1.8)};
  const std::size_t n = 200;
  const std::vector<double> log_hdr = Uniform(3 * n, -6.0, 4.0, 31);
  std::vector<double> ldr(3 * n), expected(3 * n);
  ReinhardForward(params.data(), 0.4, log_hdr.data(), n, ldr.data());
  int clipped = 0;
  for (std::size_t i = 0; i < n; ++i) {
    Textbook(params.data(), 0.4, &log_hdr[3 * i], &expected[3 * i]);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(ldr[3 * i + c], expected[3 * i + c], 1e-12) << i;
      clipped += expected[3 * i + c] == 1.0;
    }
  }
  EXPECT_GT(clipped, 10);  // the clip was exercised too
}

TEST(ReinhardToneMapper, TheWhitePointMapsToWhiteAndColourRatiosAreKept) {
  const double white = 3.0;
  const std::vector<double> params = {std::log(0.5), std::log(white), 0.0};  // gamma 1
  // A grey pixel with scaled luminance exactly L_white: L_d = 1.
  const double grey = std::log(white / 0.5);
  std::vector<double> log_hdr = {grey, grey, grey}, ldr(3);
  ReinhardForward(params.data(), 0.0, log_hdr.data(), 1, ldr.data());
  for (double y : ldr) EXPECT_NEAR(y, 1.0, 1e-12);
  log_hdr = {grey - 0.1, grey - 0.1, grey - 0.1};
  ReinhardForward(params.data(), 0.0, log_hdr.data(), 1, ldr.data());
  EXPECT_LT(ldr[0], 0.99);
  // A coloured, unclipped pixel keeps its channel ratios (gamma 1).
  log_hdr = {std::log(0.02), std::log(0.05), std::log(0.1)};
  ReinhardForward(params.data(), 0.0, log_hdr.data(), 1, ldr.data());
  EXPECT_NEAR(ldr[1] / ldr[0], 2.5, 1e-9);
  EXPECT_NEAR(ldr[2] / ldr[0], 5.0, 1e-9);
}

TEST(ReinhardToneMapper, BackwardMatchesFiniteDifferences) {
  const std::vector<double> params = {std::log(0.3), std::log(2.5), std::log(2.0)};
  const std::size_t n = 8;
  const double log_e = -0.3;
  std::vector<double> log_hdr = Uniform(3 * n, -4.0, 3.0, 41);
  const std::vector<double> weights = Uniform(3 * n, -1.0, 1.0, 42);
  std::vector<double> d_log_hdr(3 * n), d_params(3, 0.0);
  ReinhardBackward(params.data(), log_e, log_hdr.data(), n, weights.data(), d_log_hdr.data(),
                   d_params.data());
  auto loss = [&](const std::vector<double>& p, const std::vector<double>& v) {
    std::vector<double> ldr(3 * n);
    ReinhardForward(p.data(), log_e, v.data(), n, ldr.data());
    return Dot(weights, ldr);
  };
  ExpectFdMatch([&](const std::vector<double>& v) { return loss(params, v); }, log_hdr, d_log_hdr);
  ExpectFdMatch([&](const std::vector<double>& p) { return loss(p, log_hdr); }, params, d_params);
  // Some outputs were clipped (zero gradient there) and some were not.
  std::vector<double> ldr(3 * n);
  ReinhardForward(params.data(), log_e, log_hdr.data(), n, ldr.data());
  EXPECT_GT(std::count(ldr.begin(), ldr.end(), 1.0), 0);
  EXPECT_GT(std::count_if(ldr.begin(), ldr.end(), [](double y) { return y < 0.9; }), 3);
}

TEST(ReinhardToneMapper, MonotonicInRadianceExposureAndOwnChannel) {
  ReinhardToneMapper mapper(Config());
  std::vector<float> grey, red;
  for (float v = -12.f; v <= 12.f; v += 0.25f) {
    grey.insert(grey.end(), {v, v, v});
    red.insert(red.end(), {v, 0.f, -1.f});
  }
  const std::size_t n = grey.size() / 3;
  std::vector<float> previous;
  for (float log_e : {-4.f, -1.f, 0.f, 1.f, 3.f}) {
    mapper.BeginFrame({0, -1, log_e});
    std::vector<float> ldr(3 * n), ldr_red(3 * n);
    mapper.Map(grey.data(), n, ldr.data());
    mapper.Map(red.data(), n, ldr_red.data());
    for (std::size_t i = 1; i < n; ++i) {
      EXPECT_GE(ldr[3 * i], ldr[3 * (i - 1)]) << i;
      EXPECT_GE(ldr_red[3 * i], ldr_red[3 * (i - 1)]) << i;
    }
    EXPECT_LT(ldr[0], 0.01f);
    EXPECT_EQ(ldr[3 * (n - 1)], 1.f);
    for (std::size_t k = 0; !previous.empty() && k < 3 * n; ++k) EXPECT_GE(ldr[k], previous[k]);
    previous = ldr;
  }
}

TEST(ReinhardToneMapper, ExtremeInputsAndParametersStayFiniteInUnitRange) {
  ReinhardToneMapper mapper(Config());
  std::vector<float> log_hdr;
  for (double r = 1e-6; r <= 1e6 * 1.0001; r *= 10) {
    log_hdr.insert(log_hdr.end(), {float(std::log(r)), 0.f, float(-std::log(r))});
  }
  const float inf = std::numeric_limits<float>::infinity();
  log_hdr.insert(log_hdr.end(), {-inf, -inf, -inf});
  log_hdr.insert(log_hdr.end(), {inf, inf, inf});
  log_hdr.insert(log_hdr.end(), {-inf, 5.f, inf});
  const std::size_t n = log_hdr.size() / 3;
  std::vector<float> ldr(3 * n), d(3 * n), dL(3 * n, 1.f);
  const std::vector<std::vector<float>> settings = {
      {std::log(0.18f), std::log(2.f), std::log(2.2f)},
      {1e3f, 1e3f, 1e3f},
      {-1e3f, -1e3f, -1e3f},
      {20.f, -20.f, -20.f}};
  for (const auto& params : settings) {
    mapper.params() = params;
    for (double exposure : {1e-4, 1e-2, 1.0, 1e3}) {
      mapper.ZeroGrad();
      mapper.BeginFrame({0, -1, float(std::log(exposure))});
      mapper.Map(log_hdr.data(), n, ldr.data());
      mapper.MapBackward(log_hdr.data(), n, dL.data(), d.data());
      EXPECT_TRUE(AllFiniteIn01(ldr)) << params[0] << " " << exposure;
      EXPECT_TRUE(AllFinite(d)) << params[0] << " " << exposure;
      EXPECT_TRUE(AllFinite(mapper.grads())) << params[0] << " " << exposure;
    }
  }
  // Parameters outside the clamp get no gradient (a box constraint).
  EXPECT_EQ(mapper.grads()[0], 0.f);
}

TEST(ReinhardToneMapper, GradientsAreIdenticalAtAnyThreadCount) {
  ReinhardToneMapper mapper(Config());
  const std::size_t n = 20000;
  const std::vector<float> log_hdr = Uniform<float>(3 * n, -6, 6, 1);
  const std::vector<float> dL = Uniform<float>(3 * n, -1, 1, 2);
  mapper.BeginFrame({0, -1, 0.1f});
  std::vector<std::vector<float>> grads, d_inputs;
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    mapper.ZeroGrad();
    std::vector<float> d(3 * n);
    mapper.MapBackward(log_hdr.data(), n, dL.data(), d.data());
    grads.push_back(mapper.grads());
    d_inputs.push_back(d);
  }
  EXPECT_NE(grads[0][0], 0.f);
  EXPECT_EQ(std::memcmp(grads[0].data(), grads[1].data(), 3 * sizeof(float)), 0);
  EXPECT_EQ(d_inputs[0], d_inputs[1]);
}

}  // namespace
}  // namespace hdr4d::baselines
