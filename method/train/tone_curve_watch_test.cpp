#include "method/train/tone_curve_watch.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "method/gaussian/constants.h"

namespace hdr4d::method {
namespace {

// A model whose DC log colours are `values` (each Gaussian grey at that value).
GaussianModel ModelWithLogColours(const std::vector<float>& values) {
  GaussianModel model;
  model.color_mode = ColorMode::kLogHdr;
  model.Resize(values.size());
  for (std::size_t i = 0; i < values.size(); ++i)
    for (int c = 0; c < 3; ++c) model.color_dc[i * 3 + c] = (values[i] - 0.5f) / kShC0;
  return model;
}

std::vector<TrainView> ViewsWithExposures(const std::vector<double>& exposures) {
  std::vector<TrainView> views(exposures.size());
  for (std::size_t i = 0; i < exposures.size(); ++i) views[i].exposure = exposures[i];
  return views;
}

TEST(ToneCurveWatch, InputRangeIsTheColoursPercentilesWidenedByTheExposures) {
  std::vector<float> values(101);
  for (int i = 0; i <= 100; ++i) values[i] = -5.0f + 0.1f * i;  // -5 .. 5
  const auto [lo, hi] = ToneCurveInputRange(ModelWithLogColours(values),
                                            ViewsWithExposures({0.125, 2.0, 32.0}));
  // 303 values (3 channels): the 1st percentile is the 4th smallest (-4.9), the 99th the 4th
  // largest (4.9).
  EXPECT_NEAR(lo, -4.9 + std::log(0.125), 1e-5);
  EXPECT_NEAR(hi, 4.9 + std::log(32.0), 1e-5);
}

TEST(ToneCurveWatch, InputRangeSkipsBadValuesAndIsNeverEmpty) {
  std::vector<float> values(50, 1.5f);
  values[3] = std::numeric_limits<float>::quiet_NaN();
  values[7] = std::numeric_limits<float>::infinity();
  // One exposure and a zero one (ignored): all colours alike, a unit of x around them.
  const auto [lo, hi] =
      ToneCurveInputRange(ModelWithLogColours(values), ViewsWithExposures({1.0, 0.0}));
  EXPECT_NEAR(lo, 1.0, 1e-5);
  EXPECT_NEAR(hi, 2.0, 1e-5);
  // No Gaussians and no usable exposure: around 0.
  const auto [lo0, hi0] = ToneCurveInputRange(GaussianModel{}, ViewsWithExposures({0.0}));
  EXPECT_NEAR(lo0, -0.5, 1e-12);
  EXPECT_NEAR(hi0, 0.5, 1e-12);
}

TEST(ToneCurveWatch, WarningSaysWhatIsFlatWhereAndTheWayOut) {
  const std::string one = FlatToneCurveWarning(
      {FlatToneCurve{.channel = 1, .time = 0.5, .level = 0.99997, .spread = 2e-5}}, "mlp",
      {-7.25, 6.5}, 1500);
  for (const char* part : {"iteration 1500", "the mlp tone curve is flat", "[-7.2, 6.5]",
                           "green at 1.000 (varies by 2.0e-05 at time 0.5)",
                           "--monotone-tone-curves", "hdr4d tone-curves"}) {
    EXPECT_NE(one.find(part), std::string::npos) << part << " in: " << one;
  }
  const std::string all = FlatToneCurveWarning(
      {FlatToneCurve{.channel = 0, .level = 1.0}, FlatToneCurve{.channel = 1, .level = 1.0},
       FlatToneCurve{.channel = 2, .time = 1.0, .level = 0.0}},
      "dtm", {-1, 1}, 500);
  EXPECT_NE(all.find("the dtm tone curves are flat over the inputs this scene gives them"),
            std::string::npos)
      << all;
  EXPECT_NE(all.find("red at 1.000 (varies by 0.0e+00 at time 0.0), green at 1.000"),
            std::string::npos)
      << all;
  EXPECT_NE(all.find(" and blue at 0.000"), std::string::npos) << all;
}

}  // namespace
}  // namespace hdr4d::method
