#include "method/run/export_ply.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/util/error.h"
#include "method/gaussian/constants.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {

GaussianModel TwoGaussians() {
  GaussianModel m;
  m.Resize(2);
  m.xyz = {0.1f, 0.2f, 0.3f, 1, 1, 1};
  m.t = {0.5f, 0.0f};
  m.log_scales = {std::log(0.1f), std::log(0.2f), std::log(0.3f), std::log(0.05f),
                  std::log(0.1f), std::log(0.1f), std::log(0.1f), std::log(0.05f)};
  m.opacity_logit = {0.0f, 0.0f};
  m.color_dc = {1, 2, 3, 0, 0, 0};
  return m;
}

// Parses the header and the float payload of a binary 3DGS ply.
struct Ply {
  std::vector<std::string> properties;
  std::vector<float> values;
  std::size_t vertices = 0;
};
Ply Read(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  Ply ply;
  std::string line;
  while (std::getline(in, line) && line != "end_header") {
    std::istringstream s(line);
    std::string word, type, name;
    s >> word;
    if (word == "element") s >> type >> ply.vertices;
    if (word == "property") s >> type >> name, ply.properties.push_back(name);
  }
  ply.values.resize(ply.vertices * ply.properties.size());
  in.read(reinterpret_cast<char*>(ply.values.data()), ply.values.size() * sizeof(float));
  return ply;
}

TEST(ExportPly, SliceHasThe3dgsLayoutAndValues) {
  testing::TempDir dir;
  const GaussianModel m = TwoGaussians();
  // At t = 0.5 only the first Gaussian is alive (the second lives around t = 0, sigma 0.05).
  EXPECT_EQ(ExportSlicePly(m, 0.5f, 1.0f, dir / "a.ply"), 1u);
  const Ply ply = Read(dir / "a.ply");
  ASSERT_EQ(ply.properties.size(), 62u);  // SH degree 3: 45 f_rest
  EXPECT_EQ(ply.properties[0], "x");
  EXPECT_EQ(ply.properties[6], "f_dc_0");
  EXPECT_EQ(ply.properties[9], "f_rest_0");
  EXPECT_EQ(ply.properties[54], "opacity");
  EXPECT_EQ(ply.properties[61], "rot_3");
  EXPECT_FLOAT_EQ(ply.values[0], 0.1f);
  EXPECT_FLOAT_EQ(ply.values[6], 1.0f);     // DC unchanged (time blocks beyond 0 are zero)
  EXPECT_NEAR(ply.values[54], 0.0f, 1e-6);  // marginal 1 at its own time: logit(0.5) = 0
  // Scales are the axis-aligned ones (identity rotations), in some order.
  std::vector<float> scales = {ply.values[55], ply.values[56], ply.values[57]};
  std::sort(scales.begin(), scales.end());
  EXPECT_NEAR(scales[0], std::log(0.1f), 1e-5);
  EXPECT_NEAR(scales[2], std::log(0.3f), 1e-5);
  // At t = 0 only the second one is alive (the first's marginal is exp(-0.5 * 0.25 / 0.0025)).
  EXPECT_EQ(ExportSlicePly(m, 0.0f, 1.0f, dir / "b.ply"), 1u);
  EXPECT_FLOAT_EQ(Read(dir / "b.ply").values[0], 1.0f);
}

TEST(ExportPly, LogHdrModelsNeedADisplayMapping) {
  testing::TempDir dir;
  GaussianModel m = TwoGaussians();
  m.color_mode = ColorMode::kLogHdr;
  EXPECT_THROW(ExportSlicePly(m, 0.5f, 1.0f, dir / "a.ply"), Error);
  // Without a tone mapper: exp(c) x exposure as sRGB, written back as the DC coefficient.
  m.color_dc.assign(m.color_dc.size(), 0.0f);  // c = 0.5 -> radiance e^0.5
  const ExportDisplay display{nullptr, {0, -1, std::log(0.25f)}};
  ASSERT_EQ(ExportSlicePly(m, 0.5f, 1.0f, dir / "b.ply", &display), 1u);
  const Ply p = Read(dir / "b.ply");
  const float expected = LinearToSrgb(std::exp(0.5f) * 0.25f);
  EXPECT_NEAR(p.values[6] * kShC0 + kColorOffset, expected, 1e-5f);
  for (int k = 9; k < 54; ++k) EXPECT_NEAR(p.values[k], 0.0f, 1e-5f) << k;  // no view dependence
}

// A view-dependent log-HDR colour keeps its view dependence in the display columns: the fitted
// SH give, in each direction, close to the display colour of the log-HDR colour there.
TEST(ExportPly, LogHdrViewDependenceIsFittedInTheDisplayColumns) {
  testing::TempDir dir;
  GaussianModel m = TwoGaussians();
  m.color_mode = ColorMode::kLogHdr;
  m.color_dc.assign(m.color_dc.size(), 0.0f);
  m.color_rest[(2 - 1) * 3 + 0] = 0.4f;  // red: + 0.4 Y_10 = 0.4 C1 z
  const ExportDisplay display{nullptr, {0, -1, std::log(0.25f)}};
  ASSERT_EQ(ExportSlicePly(m, 0.5f, 1.0f, dir / "v.ply", &display), 1u);
  const Ply p = Read(dir / "v.ply");
  const float c1 = 0.4886025f;
  for (float z : {-1.0f, 0.0f, 1.0f}) {
    const float want = LinearToSrgb(std::exp(0.5f + 0.4f * c1 * z) * 0.25f);
    // Red's SH: DC at 6, degree 1 at 9 (y), 10 (z), 11 (x) with the 3DGS signs.
    const float got = kColorOffset + kShC0 * p.values[6] + c1 * z * p.values[10];
    EXPECT_NEAR(got, want, 0.01f) << "z " << z;
  }
  EXPECT_GT(std::abs(p.values[10]), 0.05f);  // the view dependence is there
}

}  // namespace
}  // namespace hdr4d::method
