// Dividing vignetting out of a camera's images: the response's Encode undoes Linearize, a
// vignetted bracket comes back to the unvignetted one within a code (saturated codes stay), the
// HDR exactly, and which cameras `auto` corrects.
#include "calibration/vignetting_correction.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/util/error.h"

namespace hdr4d {
namespace {

// A gamma-like response with a flat toe (codes 0-3) and a flat top (253-255), as recovered
// curves have.
CameraResponse GammaResponse() {
  CameraResponse response;
  response.inverse.resize(3);
  for (int c = 0; c < 3; ++c)
    for (int z = 0; z < kResponseCodes; ++z) {
      const double code = std::clamp(z, 3, 253) / 255.0;
      response.inverse[c][z] = std::pow(code / (128 / 255.0), 2.2 + 0.1 * c);
    }
  return response;
}

RigCamera Camera() {
  RigCamera camera;
  camera.name = "cam0";
  camera.width = 64;
  camera.height = 48;
  camera.intrinsics = {60, 30.5, 25.0};  // principal point off the centre
  return camera;
}

TEST(VignettingCorrection, EncodeUndoesLinearize) {
  const CameraResponse response = GammaResponse();
  for (int c = 0; c < 3; ++c)
    for (int z = 4; z <= 253; ++z)
      EXPECT_NEAR(response.Encode(c, response.Linearize(c, z / 255.0)) * 255, z, 1e-6) << c << " " << z;
  EXPECT_EQ(response.Encode(0, 0.0), 0.0);
  EXPECT_EQ(response.Encode(0, -1.0), 0.0);
  EXPECT_EQ(response.Encode(0, 1e9), 1.0);
  EXPECT_EQ(response.Encode(0, std::nan("")), 0.0);
}

TEST(VignettingCorrection, CornerRadiusIsOneAtTheFarthestCornerAndZeroAtThePrincipalPoint) {
  const RigCamera camera = Camera();
  EXPECT_NEAR(CornerRadius2(camera, 30.5, 25.0), 0, 1e-12);
  // The farthest corner from (30.5, 25) is (64, 0) (dx 33.5, dy 25), not on the diagonal
  // through (0, 0) and (64, 48).
  EXPECT_NEAR(CornerRadius2(camera, 64, 0), 1, 1e-12);
  EXPECT_LT(CornerRadius2(camera, 64, 48), 1);
  EXPECT_LT(CornerRadius2(camera, 0, 0), 1);
  EXPECT_NEAR(VignettingFalloff(camera, 0.3, 64, 0), 0.7, 1e-12);
  EXPECT_EQ(VignettingFalloff(camera, 0.95, 64, 0), 0.1);  // floored
}

TEST(VignettingCorrection, BracketsAndHdrComeBackToTheUnvignettedImages) {
  const RigCamera camera = Camera();
  const CameraResponse response = GammaResponse();
  constexpr double kV = 0.3;
  Image radiance(camera.width, camera.height, 3), hdr(camera.width, camera.height, 3);
  Image truth_ldr(camera.width, camera.height, 3), ldr(camera.width, camera.height, 3);
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x)
      for (int c = 0; c < 3; ++c) {
        // Radiance from dark to past saturation across the image, a stripe at each channel.
        const double l = 0.02 * std::exp(0.09 * x + 0.02 * y + 0.3 * c);
        const double fall = 1 - kV * CornerRadius2(camera, x + 0.5, y + 0.5);
        radiance.at(x, y, c) = static_cast<float>(l);
        hdr.at(x, y, c) = static_cast<float>(l * fall);
        truth_ldr.at(x, y, c) = static_cast<float>(std::round(response.Encode(c, l) * 255) / 255);
        ldr.at(x, y, c) = static_cast<float>(std::round(response.Encode(c, l * fall) * 255) / 255);
      }
  const Image restored_hdr = DevignetteLinear(hdr, camera, kV);
  const Image restored_ldr = DevignetteDisplay(ldr, camera, kV, response);
  int saturated = 0;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x)
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(restored_hdr.at(x, y, c), radiance.at(x, y, c), 1e-5 * radiance.at(x, y, c));
        if (ldr.at(x, y, c) >= 1) {  // clipped in the capture: nothing to restore
          EXPECT_EQ(restored_ldr.at(x, y, c), 1.0f);
          ++saturated;
          continue;
        }
        // Within the rounding of both codes: half a code of the truth's, and half a code of the
        // vignetted one stretched by the curve between the two exposures (< 1.2 for 1 / 0.7).
        // Codes in the curve's flat toe and top (0-3, 253-255) are one exposure each: left out.
        if (truth_ldr.at(x, y, c) > 5 / 255.0 && truth_ldr.at(x, y, c) < 250 / 255.0) {
          EXPECT_NEAR(restored_ldr.at(x, y, c) * 255, truth_ldr.at(x, y, c) * 255, 1.2) << x << " " << y << " " << c;
        }
      }
  EXPECT_GT(saturated, 0);
}

TEST(VignettingCorrection, AutoCorrectsOnlyAFalloffTheDataResolve) {
  // Large and resolved; below 0.05; negative; resolved but at 3 standard errors; not a number;
  // exactly at both lines; no error given.
  const std::vector<double> estimate = {0.2, 0.04, -0.03, 0.075, std::nan(""), 0.06, 0.3};
  const std::vector<double> error = {0.01, 0.001, 0.01, 0.025, 0.01, 0.015};
  EXPECT_EQ(VignettingToApply(estimate, error, VignettingCorrection::kAuto),
            (std::vector<double>{0.2, 0, 0, 0, 0, 0.06, 0}));
  EXPECT_EQ(VignettingToApply(estimate, error, VignettingCorrection::kAlways),
            (std::vector<double>{0.2, 0.04, 0, 0.075, 0, 0.06, 0.3}));
  EXPECT_EQ(VignettingToApply(estimate, error, VignettingCorrection::kNever), (std::vector<double>(7, 0.0)));
  EXPECT_EQ(ParseVignettingCorrection("on"), VignettingCorrection::kAlways);
  EXPECT_THROW(ParseVignettingCorrection("yes"), Error);
}

TEST(VignettingCorrection, AnImageOfAnotherSizeIsRefusedNamingTheCamera) {
  const Image wrong(10, 10, 3);
  try {
    DevignetteLinear(wrong, Camera(), 0.2);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cam0"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hdr4d
