// The HDR head's pieces (hdr_head.h): the colour stage's offset (forward: only the HDR channels
// move; backward: dL/d(offset) against finite differences in double) and the checkpoint reader's
// errors. The whole mode is tested through the trainer in trainer_hdr_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "method/render/hdr_color_stage.h"
#include "method/render/learned_background.h"
#include "method/tonemap/tone_mapper_registry.h"
#include "method/train/checkpoint.h"
#include "method/train/hdr_head_fit.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {
using hdr4d::testing::ErrorOf;

struct StageCase {
  std::vector<float> colors{-1.0f, 0.5f, 2.0f, 0.2f, -3.0f, 1.0f, 0.0f, 0.7f, -0.4f};
  std::vector<std::uint32_t> visible{0, 2};  // Gaussian 1 is not in view
  std::unique_ptr<ToneMapper> tm;
  std::optional<HdrColorStage> stage;
  StageCase() {
    ToneMapperConfig tc;
    tc.context_window = 2;
    tc.num_times = 2;
    tm = MakeToneMapper(tc);
    stage.emplace(tm.get(), true);
    stage->SetFrame({.time_index = 1, .log_exposure = std::log(2.0f)}, false);
  }
  std::vector<float> Forward(const float* offset) {
    stage->SetHdrOffset(offset, nullptr);
    std::vector<float> f(3 * 6, -7.0f);
    stage->Forward(colors.data(), 3, visible, f.data());
    return f;
  }
};

TEST(HdrHead, OffsetMovesOnlyTheHdrChannels) {
  StageCase k;
  ASSERT_EQ(k.stage->feature_channels(), 6);
  const std::vector<float> offset{0.5f, -1.0f, 2.0f, 9.0f, 9.0f, 9.0f, -0.25f, 0.0f, 1.5f};
  const std::vector<float> plain = k.Forward(nullptr);
  const std::vector<float> moved = k.Forward(offset.data());
  for (std::uint32_t i : k.visible) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_FLOAT_EQ(moved[i * 6 + c], std::exp(k.colors[i * 3 + c] + offset[i * 3 + c]));
      EXPECT_EQ(moved[i * 6 + 3 + c], plain[i * 6 + 3 + c]);  // the tone-mapped LDR: unchanged
    }
  }
}

// L = sum over the visible Gaussians' features of g * feature; dL/d(offset) from the stage's
// backward against central differences of the same L evaluated in double.
TEST(HdrHead, OffsetGradientMatchesFiniteDifferences) {
  StageCase k;
  std::vector<float> offset{0.5f, -1.0f, 2.0f, 0.0f, 0.0f, 0.0f, -0.25f, 0.1f, 1.5f};
  std::vector<float> g(3 * 6);
  for (std::size_t q = 0; q < g.size(); ++q) g[q] = 0.3f * std::sin(1.7f * float(q) + 0.2f);
  k.Forward(offset.data());
  std::vector<float> grad(offset.size(), -5.0f), dcolors(offset.size(), 0.0f);
  k.stage->SetHdrOffset(offset.data(), grad.data());
  k.stage->Backward(k.colors.data(), 3, k.visible, g.data(), dcolors.data());
  const auto loss = [&](const std::vector<double>& d) {  // the HDR channels' part, in double
    double l = 0;
    for (std::uint32_t i : k.visible)
      for (int c = 0; c < 3; ++c) l += g[i * 6 + c] * std::exp(double(k.colors[i * 3 + c]) + d[i * 3 + c]);
    return l;
  };
  for (std::uint32_t i : k.visible) {
    for (int c = 0; c < 3; ++c) {
      std::vector<double> up(offset.begin(), offset.end()), down = up;
      const double h = 1e-6;
      up[i * 3 + c] += h;
      down[i * 3 + c] -= h;
      const double fd = (loss(up) - loss(down)) / (2 * h);
      EXPECT_NEAR(grad[i * 3 + c], fd, 1e-5 * std::max(1.0, std::abs(fd))) << i << " " << c;
    }
  }
  for (int c = 0; c < 3; ++c) EXPECT_EQ(grad[3 + c], -5.0f);  // not in view: not written
}

// The learned background's HDR offset: the HDR channels show exp(b + d), the tone-mapped ones
// TM(b + log e) unchanged; dL/dd against central differences in double.
TEST(HdrHead, BackgroundOffsetMovesOnlyTheHdrAndMatchesFiniteDifferences) {
  StageCase k;  // its tone mapper, at the stage's frame (begun by a forward)
  k.Forward(nullptr);
  LearnedBackground bg({-1.0f, 0.5f, 2.0f}, /*log_hdr=*/true, k.tm.get());
  std::vector<float> plain, moved;
  bg.Forward(6, &plain);
  const std::vector<float> d{0.3f, -0.7f, 1.1f};
  std::vector<float> grad(3, 0.0f);
  bg.SetHdrOffset(d.data(), grad.data());
  bg.Forward(6, &moved);
  for (int c = 0; c < 3; ++c) {
    EXPECT_FLOAT_EQ(moved[c], std::exp(bg.params()[c] + d[c]));
    EXPECT_EQ(moved[3 + c], plain[3 + c]);
  }
  const std::vector<float> dL{0.4f, -1.3f, 0.25f, 0.9f, -0.6f, 0.2f};
  bg.Backward(6, dL.data());
  const auto loss = [&](const std::vector<double>& x) {  // the HDR channels' part, in double
    double l = 0;
    for (int c = 0; c < 3; ++c) l += dL[c] * std::exp(double(bg.params()[c]) + x[c]);
    return l;
  };
  for (int c = 0; c < 3; ++c) {
    std::vector<double> up(d.begin(), d.end()), down = up;
    const double h = 1e-6;
    up[c] += h;
    down[c] -= h;
    const double fd = (loss(up) - loss(down)) / (2 * h);
    EXPECT_NEAR(grad[c], fd, 1e-5 * std::max(1.0, std::abs(fd))) << c;
  }
}

TEST(HdrHead, CheckpointReaderNamesTheFileAndTheProblem) {
  Checkpoint c;
  c.extra_floats = {{}, {}, {}};
  EXPECT_TRUE(ReadHdrHead(c, 2, "run/checkpoint.bin").empty());  // a run without a head
  c.extra_floats.push_back({0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f});
  c.trainer = nlohmann::json::object();
  std::string e = ErrorOf([&] { ReadHdrHead(c, 2, "run/checkpoint.bin"); });
  EXPECT_NE(e.find("run/checkpoint.bin"), std::string::npos) << e;
  EXPECT_NE(e.find(kHdrHeadScaleKey), std::string::npos) << e;
  c.trainer[kHdrHeadScaleKey] = 1.5;
  const HdrHead head = ReadHdrHead(c, 2, "run/checkpoint.bin");
  EXPECT_EQ(head.offset.size(), 6u);
  EXPECT_FLOAT_EQ(head.log_scale, 1.5f);
  e = ErrorOf([&] { ReadHdrHead(c, 3, "run/checkpoint.bin"); });
  EXPECT_NE(e.find("6 offsets for 3 Gaussians"), std::string::npos) << e;
  c.extra_floats[3][4] = std::numeric_limits<float>::quiet_NaN();
  e = ErrorOf([&] { ReadHdrHead(c, 2, "run/checkpoint.bin"); });
  EXPECT_NE(e.find("non-finite"), std::string::npos) << e;
  c.extra_floats[3][4] = 0.0f;
  c.trainer[kHdrHeadScaleKey] = 1e9;
  e = ErrorOf([&] { ReadHdrHead(c, 2, "run/checkpoint.bin"); });
  EXPECT_NE(e.find("not a finite log factor"), std::string::npos) << e;
  // The background offset: optional, 3 finite numbers, only beside a learned background.
  c.trainer[kHdrHeadScaleKey] = 0.5;
  c.trainer[kHdrHeadBackgroundKey] = {0.1, -0.2, 0.3};
  e = ErrorOf([&] { ReadHdrHead(c, 2, "run/checkpoint.bin"); });
  EXPECT_NE(e.find("no learned background"), std::string::npos) << e;
  c.trainer[kLearnedBackgroundKey] = {-1.0, -1.0, -1.0};
  EXPECT_EQ(ReadHdrHead(c, 2, "run/checkpoint.bin").background.size(), 3u);
  c.trainer[kHdrHeadBackgroundKey] = {0.1, -0.2};
  e = ErrorOf([&] { ReadHdrHead(c, 2, "run/checkpoint.bin"); });
  EXPECT_NE(e.find("must hold 3 numbers"), std::string::npos) << e;
  c.trainer[kHdrHeadBackgroundKey] = {0.1, -0.2, "x"};
  e = ErrorOf([&] { ReadHdrHead(c, 2, "run/checkpoint.bin"); });
  EXPECT_NE(e.find("not a finite log offset"), std::string::npos) << e;
}

}  // namespace
}  // namespace hdr4d::method
