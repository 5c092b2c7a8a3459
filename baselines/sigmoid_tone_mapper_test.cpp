#include "baselines/sigmoid_tone_mapper.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "baselines/test_util.h"
#include "core/util/parallel.h"
#include "method/optim/adam.h"

namespace hdr4d::baselines {
namespace {

using namespace testing;  // baselines/test_util.h

method::ToneMapperConfig Config(int num_images) {
  method::ToneMapperConfig config;
  config.kind = "sigmoid";
  config.num_images = num_images;
  return config;
}

TEST(SigmoidToneMapper, OneZeroOffsetPerTrainingImage) {
  SigmoidToneMapper mapper(Config(4));
  EXPECT_EQ(mapper.params(), std::vector<float>(4, 0.f));
  EXPECT_EQ(mapper.grads().size(), 4u);
  EXPECT_TRUE(mapper.pointwise());
  EXPECT_FLOAT_EQ(mapper.learning_rate(), 0.01f);
  EXPECT_TRUE(SigmoidToneMapper(Config(0)).params().empty());
}

TEST(SigmoidToneMapper, IsTheLogisticOfLogRadiancePlusExposurePlusOffset) {
  SigmoidToneMapper mapper(Config(3));
  mapper.params() = {0.5f, -1.f, 2.f};
  const std::vector<float> log_hdr = {-2.f, 0.f, 1.f};
  std::vector<float> ldr(3);
  mapper.BeginFrame({0, 1, 0.25f});
  mapper.Map(log_hdr.data(), 1, ldr.data());
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(ldr[c], 1.0 / (1.0 + std::exp(-(log_hdr[c] + 0.25 - 1.0))), 1e-7);
  }
  // A view that is no training image uses the mean offset (0.5).
  mapper.BeginFrame({0, -1, 0.25f});
  EXPECT_FLOAT_EQ(mapper.FrameOffset(), 0.5f);
  mapper.Map(log_hdr.data(), 1, ldr.data());
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(ldr[c], 1.0 / (1.0 + std::exp(-(log_hdr[c] + 0.25 + 0.5))), 1e-7);
  }
  // Without training images: a plain sigmoid.
  SigmoidToneMapper plain(Config(0));
  plain.BeginFrame({0, -1, 0.f});
  plain.Map(log_hdr.data(), 1, ldr.data());
  EXPECT_NEAR(ldr[1], 0.5, 1e-7);
}

TEST(SigmoidToneMapper, BackwardMatchesFiniteDifferences) {
  const std::size_t n = 6;
  const double log_e = 1.3;
  const std::vector<double> log_hdr = Uniform(3 * n, -4.0, 3.0, 21);
  const std::vector<double> weights = Uniform(3 * n, -1.0, 1.0, 22);
  std::vector<double> offset = {-0.7};
  std::vector<double> d_log_hdr(3 * n), d_offset = {0.0};
  SigmoidBackward(offset[0], log_e, log_hdr.data(), n, weights.data(), d_log_hdr.data(),
                  d_offset.data());
  auto loss = [&](const std::vector<double>& v, double o) {
    std::vector<double> ldr(3 * n);
    SigmoidForward(o, log_e, v.data(), n, ldr.data());
    return Dot(weights, ldr);
  };
  ExpectFdMatch([&](const std::vector<double>& v) { return loss(v, offset[0]); }, log_hdr,
                d_log_hdr);
  ExpectFdMatch([&](const std::vector<double>& o) { return loss(log_hdr, o[0]); }, offset,
                d_offset);
}

TEST(SigmoidToneMapper, ParameterGradientGoesToTheFramesImageOrSpreadsOverTheMean) {
  SigmoidToneMapper mapper(Config(4));
  mapper.params() = {0.1f, 0.2f, -0.3f, 0.4f};
  const std::vector<float> log_hdr = Uniform<float>(30, -2, 2, 3);
  const std::vector<float> dL = Uniform<float>(30, -1, 1, 4);
  mapper.BeginFrame({0, 2, -0.5f});
  mapper.MapBackward(log_hdr.data(), 10, dL.data(), nullptr);
  float expected = 0.f;
  SigmoidBackward(-0.3f, -0.5f, log_hdr.data(), 10, dL.data(), static_cast<float*>(nullptr),
                  &expected);
  EXPECT_NE(expected, 0.f);
  EXPECT_EQ(mapper.grads(), (std::vector<float>{0.f, 0.f, expected, 0.f}));
  // Mean offset: d mean / d offset_i = 1/4 for each.
  mapper.ZeroGrad();
  mapper.BeginFrame({0, -1, -0.5f});
  mapper.MapBackward(log_hdr.data(), 10, dL.data(), nullptr);
  float through_mean = 0.f;
  SigmoidBackward(0.1f, -0.5f, log_hdr.data(), 10, dL.data(), static_cast<float*>(nullptr),
                  &through_mean);
  for (float g : mapper.grads()) EXPECT_NEAR(g, through_mean / 4, 1e-7);
}

TEST(SigmoidToneMapper, MonotonicInRadianceAndExposure) {
  SigmoidToneMapper mapper(Config(1));
  mapper.params() = {0.3f};
  std::vector<float> log_hdr;
  for (float v = -10.f; v <= 10.f; v += 0.25f) log_hdr.insert(log_hdr.end(), {v, v, v});
  const std::size_t n = log_hdr.size() / 3;
  std::vector<float> previous;
  for (float log_e : {-3.f, -1.f, 0.f, 2.f}) {
    mapper.BeginFrame({0, 0, log_e});
    std::vector<float> ldr(3 * n);
    mapper.Map(log_hdr.data(), n, ldr.data());
    for (std::size_t i = 1; i < n; ++i) EXPECT_GT(ldr[3 * i], ldr[3 * (i - 1)]) << i;
    for (std::size_t k = 0; !previous.empty() && k < 3 * n; ++k) {
      EXPECT_GE(ldr[k], previous[k]);
    }
    previous = ldr;
  }
}

TEST(SigmoidToneMapper, ExtremeAndInfiniteInputsStayFiniteInUnitRange) {
  SigmoidToneMapper mapper(Config(2));
  std::vector<float> log_hdr;
  for (double r = 1e-6; r <= 1e6 * 1.0001; r *= 10) {
    log_hdr.insert(log_hdr.end(), {float(std::log(r)), 0.f, float(-std::log(r))});
  }
  const float inf = std::numeric_limits<float>::infinity();
  log_hdr.insert(log_hdr.end(), {-inf, inf, 0.f});
  const std::size_t n = log_hdr.size() / 3;
  std::vector<float> ldr(3 * n), d(3 * n), dL(3 * n, 1.f);
  for (double exposure : {1e-4, 1e-1, 1.0, 1e3}) {
    for (float offset : {0.f, 50.f, -50.f}) {
      mapper.params() = {offset, 0.f};
      mapper.ZeroGrad();
      mapper.BeginFrame({0, 0, float(std::log(exposure))});
      mapper.Map(log_hdr.data(), n, ldr.data());
      mapper.MapBackward(log_hdr.data(), n, dL.data(), d.data());
      EXPECT_TRUE(AllFiniteIn01(ldr));
      EXPECT_TRUE(AllFinite(d));
      EXPECT_TRUE(AllFinite(mapper.grads()));
      EXPECT_EQ(d[3 * (n - 1)], 0.f);  // log 0: clamped, no gradient
      if (offset == 0.f) {             // log 0 maps to black, +inf to white
        EXPECT_LT(ldr[3 * (n - 1)], 1e-6f);
        EXPECT_GT(ldr[3 * (n - 1) + 1], 1.f - 1e-6f);
      }
    }
  }
}

TEST(SigmoidToneMapper, GradientsAreIdenticalAtAnyThreadCount) {
  SigmoidToneMapper mapper(Config(3));
  const std::size_t n = 20000;
  const std::vector<float> log_hdr = Uniform<float>(3 * n, -6, 6, 1);
  const std::vector<float> dL = Uniform<float>(3 * n, -1, 1, 2);
  mapper.BeginFrame({0, 1, 0.1f});
  std::vector<std::vector<float>> grads;
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    mapper.ZeroGrad();
    mapper.MapBackward(log_hdr.data(), n, dL.data(), nullptr);
    grads.push_back(mapper.grads());
  }
  EXPECT_NE(grads[0][1], 0.f);
  EXPECT_EQ(std::memcmp(grads[0].data(), grads[1].data(), grads[0].size() * sizeof(float)), 0);
}

// Images whose recorded exposures are off by a per-image factor: the offsets learn the error
// (relative to one another; the radiance here is held fixed, so absolutely too).
TEST(SigmoidToneMapper, LearnsPerImageExposureErrors) {
  const std::vector<float> truth = {0.4f, -0.6f, 0.1f};
  SigmoidToneMapper mapper(Config(3));
  method::Adam adam;
  adam.AddGroup({"tone", mapper.params().data(), mapper.grads().data(), 3, mapper.learning_rate()});
  const std::size_t n = 50;
  const std::vector<float> log_hdr = Uniform<float>(3 * n, -3, 3, 9);
  std::vector<float> ldr(3 * n), target(3 * n), dL(3 * n);
  for (int step = 0; step < 300; ++step) {
    mapper.ZeroGrad();
    for (int i = 0; i < 3; ++i) {
      SigmoidForward(truth[i], 0.f, log_hdr.data(), n, target.data());
      mapper.BeginFrame({0, i, 0.f});
      mapper.Map(log_hdr.data(), n, ldr.data());
      for (std::size_t k = 0; k < 3 * n; ++k) dL[k] = 2 * (ldr[k] - target[k]);
      mapper.MapBackward(log_hdr.data(), n, dL.data(), nullptr);
    }
    adam.Step();
  }
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(mapper.params()[i], truth[i], 0.02) << i;
}

}  // namespace
}  // namespace hdr4d::baselines
