#include "calibration/response_recovery.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/photo.hpp>
#include <random>

#include "core/radiometry/crf.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

// A static scene with radiance spanning ~10 stops, photographed through `crf` at each exposure
// and quantised to 8 bits (per channel a different radiance scale so channels differ).
std::vector<Bracket> Stack(const Crf& crf, const std::vector<double>& exposures, unsigned seed) {
  const int w = 64, h = 48;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> log_radiance(std::log(0.01), std::log(20.0));
  Image radiance(w, h, 3);
  for (float& v : radiance.values()) v = static_cast<float>(std::exp(log_radiance(rng)));
  std::vector<Bracket> stack;
  for (double t : exposures) {
    Bracket b;
    b.exposure = t;
    b.name = "bracket t=" + std::to_string(t);
    b.image = Image(w, h, 3, Encoding::kSrgb);
    for (std::size_t i = 0; i < radiance.size(); ++i)
      b.image.data()[i] = std::round(crf.Apply(radiance.data()[i] * t) * 255.0) / 255.0f;
    stack.push_back(std::move(b));
  }
  return stack;
}

// Largest |ln x(z) - ln x_true(z)| over mid codes, both normalised at code 128.
double MaxLogError(const std::array<double, kResponseCodes>& x, const Crf& crf) {
  const double mid = crf.Inverse(128 / 255.0);
  double worst = 0;
  for (int z = 16; z <= 240; ++z)
    worst = std::max(worst, std::abs(std::log(x[z]) - std::log(crf.Inverse(z / 255.0) / mid)));
  return worst;
}

const std::vector<double> kExposures = {1.0 / 64, 1.0 / 16, 1.0 / 4, 1.0, 4.0};

TEST(ResponseRecovery, DebevecRecoversAKnownCurve) {
  const FilmicCrf crf(1.5, 0.18);
  const CameraResponse r = RecoverResponse({Stack(crf, kExposures, 1)});
  ASSERT_EQ(r.inverse.size(), 3u);
  for (int c = 0; c < 3; ++c) EXPECT_LT(MaxLogError(r.inverse[c], crf), 0.08) << "channel " << c;
  // A different curve is far off: the check can fail.
  EXPECT_GT(MaxLogError(r.inverse[0], GammaCrf(1.0)), 0.3);
}

TEST(ResponseRecovery, RobertsonRecoversAKnownCurve) {
  const GammaCrf crf(2.2);
  ResponseOptions options;
  options.robertson = true;
  const CameraResponse r = RecoverResponse({Stack(crf, kExposures, 2)}, options);
  EXPECT_EQ(r.method, "robertson");
  // Robertson's fixed point on 8-bit data is biased code by code (about +-14% here, where
  // Debevec-Malik stays under 8%): the price of no smoothness prior.
  for (int c = 0; c < 3; ++c) EXPECT_LT(MaxLogError(r.inverse[c], crf), 0.2) << "channel " << c;
  EXPECT_GT(MaxLogError(r.inverse[0], GammaCrf(1.0)), 0.5);
}

TEST(ResponseRecovery, AgreesWithOpenCvCalibrateDebevec) {
  const GammaCrf crf(2.2);
  const auto stack = Stack(crf, kExposures, 3);
  std::vector<cv::Mat> images;
  std::vector<float> times;
  for (const Bracket& b : stack) {
    cv::Mat m(b.image.height(), b.image.width(), CV_8UC3);
    for (int y = 0; y < m.rows; ++y)
      for (int x = 0; x < m.cols; ++x)
        for (int c = 0; c < 3; ++c)  // OpenCV's channel order is BGR
          m.at<cv::Vec3b>(y, x)[2 - c] = static_cast<uchar>(CodeOf(b.image.at(x, y, c)));
    images.push_back(m);
    times.push_back(static_cast<float>(b.exposure));
  }
  cv::Mat cv_response;
  cv::createCalibrateDebevec(200, 30.0f, true)->process(images, cv_response, times);
  const CameraResponse ours = RecoverResponse({stack});
  for (int c = 0; c < 3; ++c) {
    const double cv_mid = cv_response.at<cv::Vec3f>(128, 0)[2 - c];
    double worst = 0;
    for (int z = 16; z <= 240; ++z) {
      const double theirs = cv_response.at<cv::Vec3f>(z, 0)[2 - c] / cv_mid;
      worst = std::max(worst, std::abs(std::log(ours.inverse[c][z] / theirs)));
    }
    EXPECT_LT(worst, 0.1) << "channel " << c;
  }
}

TEST(ResponseRecovery, BadStacksAreClearErrors) {
  const GammaCrf crf(2.2);
  auto stack = Stack(crf, {0.1, 0.4}, 4);
  auto repeated = stack;
  repeated[1].exposure = 0.1;
  EXPECT_NE(testing::ErrorOf([&] { RecoverResponse({repeated}); }).find("same exposure time"),
            std::string::npos);
  auto bad = stack;
  bad[0].exposure = 0;
  EXPECT_NE(testing::ErrorOf([&] { RecoverResponse({bad}); }).find("not a positive number"),
            std::string::npos);
  auto one = stack;
  one.pop_back();
  EXPECT_NE(testing::ErrorOf([&] { RecoverResponse({one}); }).find("at least two brackets"),
            std::string::npos);
  auto resized = stack;
  resized[1].image = Image(10, 10, 3);
  EXPECT_NE(testing::ErrorOf([&] { RecoverResponse({resized}); }).find("differs"), std::string::npos);
}

TEST(ResponseRecovery, CsvReadsBackAsATableCrf) {
  testing::TempDir dir;
  const CameraResponse r = RecoverResponse({Stack(GammaCrf(2.2), kExposures, 5)});
  WriteResponseCsv((dir / "response.csv").string(), r);
  WriteResponsePlot((dir / "response.png").string(), r);
  EXPECT_TRUE(std::filesystem::exists(dir / "response.png"));
}

}  // namespace
}  // namespace hdr4d
