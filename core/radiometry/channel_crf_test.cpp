#include "core/radiometry/channel_crf.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

#include "tests/testing.h"

namespace hdr4d {
namespace {

// calibrate's layout: code,r,g,b with gamma 1.8, 2.2 and 2.6 curves (x(128) = 1).
std::string PerChannelCsv(bool with_repeat = false) {
  std::string text = "# inverse camera response\ncode,r,g,b\n";
  const double gammas[3] = {1.8, 2.2, 2.6};
  for (int z = 0; z < 256; ++z) {
    const int value_of = with_repeat && z == 201 ? 200 : z;  // 201 printed equal to 200
    text += std::to_string(z);
    for (double g : gammas) text += fmt::format(",{:.9g}", std::pow(value_of / 128.0, g));
    text += "\n";
  }
  return text;
}

TEST(ChannelCrf, CalibratesResponseCsvGivesOneCurvePerChannel) {
  testing::TempDir dir;
  testing::WriteTextFile(dir / "response.csv", PerChannelCsv());
  const auto curves = ParseChannelCrfs("table:" + (dir / "response.csv").string());
  ASSERT_EQ(curves.size(), 3u);
  const double gammas[3] = {1.8, 2.2, 2.6};
  for (int c = 0; c < 3; ++c) {
    const double x = curves[c]->Inverse(100 / 255.0);
    EXPECT_NEAR(x, std::pow(100 / 128.0, gammas[c]), 1e-6) << c;
  }
  // A single-curve user gets the geometric mean (gamma 2.2 here).
  const auto one = TableCrf::FromCsv((dir / "response.csv").string());
  EXPECT_NEAR(one->Inverse(100 / 255.0), std::pow(100 / 128.0, 2.2), 1e-6);
  // Other specs stay one curve.
  EXPECT_EQ(ParseChannelCrfs("gamma:2.2").size(), 1u);
}

TEST(ChannelCrf, EqualNeighboursFromPrintingAreAcceptedBadRowsAreNot) {
  testing::TempDir dir;
  testing::WriteTextFile(dir / "repeat.csv", PerChannelCsv(true));
  EXPECT_EQ(ParseChannelCrfs("table:" + (dir / "repeat.csv").string()).size(), 3u);
  testing::WriteTextFile(dir / "gap.csv", "code,r,g\n0,0,0\n2,1,1\n");
  EXPECT_NE(testing::ErrorOf([&] { ReadPerChannelResponse((dir / "gap.csv").string()); }).find("gap.csv:3: code '2' where 1"),
            std::string::npos);
  testing::WriteTextFile(dir / "down.csv", "code,r,g\n0,0,0\n1,1,1\n2,0.5,1\n");
  EXPECT_NE(testing::ErrorOf([&] { ReadPerChannelResponse((dir / "down.csv").string()); }).find("must not decrease"),
            std::string::npos);
  testing::WriteTextFile(dir / "short.csv", "code,r,g\n0,0,0\n1,1\n");
  EXPECT_NE(testing::ErrorOf([&] { ReadPerChannelResponse((dir / "short.csv").string()); }).find("2 fields"),
            std::string::npos);
}

}  // namespace
}  // namespace hdr4d
