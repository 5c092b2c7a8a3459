#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

#include "core/util/error.h"
#include "method/render/view_renderer.h"
#include "method/run/export_ply.h"
#include "method/run/gaussian_4d_ply.h"
#include "method/run/gaussian_ply_reader.h"
#include "method/run/tone_tables.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {

// A log-HDR 4D model of `n` Gaussians in front of a camera at the origin looking down +z (CV).
GaussianModel RandomModel(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1, 1);
  GaussianModel m;
  m.color_mode = ColorMode::kLogHdr;
  m.Resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    m.xyz[i * 3] = u(rng), m.xyz[i * 3 + 1] = u(rng), m.xyz[i * 3 + 2] = 4 + u(rng);
    m.t[i] = 0.5f + 0.5f * u(rng);
    for (int a = 0; a < 4; ++a) m.log_scales[i * 4 + a] = -2.5f + 0.5f * u(rng);
    for (int a = 0; a < 4; ++a) m.rot_left[i * 4 + a] = u(rng), m.rot_right[i * 4 + a] = u(rng);
    m.opacity_logit[i] = 2 * u(rng);
  }
  for (float& c : m.color_dc) c = 3 * u(rng);
  for (float& c : m.color_rest) c = 0.3f * u(rng);
  return m;
}

Camera TestCamera() {
  Camera cam;
  cam.intrinsics = PinholeIntrinsics::FromFovX(1.0, 48, 40);
  cam.world_from_cam_gl = WorldFromCamGlFromCv(Eigen::Matrix4d::Identity());
  return cam;
}

std::vector<float> RenderHdr(const GaussianModel& m, float time) {
  RenderOptions options;
  options.sh_degree = m.basis.max_sh_degree;
  options.time_degree = m.temporal ? m.basis.max_time_degree : 0;
  ResolvedHdrTraining resolved;  // HDR colours, no tone mapper
  ViewRenderer renderer(m, nullptr, resolved, options, 0.0f);
  std::vector<float> hdr;
  renderer.Render(TestCamera(), time, {}, nullptr, &hdr);
  return hdr;
}

TEST(GaussianPly, FourDLayoutReadsBackBitForBit) {
  testing::TempDir dir;
  const GaussianModel m = RandomModel(50, 1);
  HdrHead head;
  head.offset.assign(150, 0.25f);
  head.log_scale = 0.5f;
  Gaussian4dPlyInfo info{1.0f, 0.01, 4.0, {0.1f, 0.2f, 0.3f}, 0.0f, &head};
  ASSERT_EQ(ExportGaussian4dPly(m, dir / "m.ply", info), 50u);
  const GaussianPly p = ReadGaussianPly(dir / "m.ply");
  EXPECT_TRUE(p.four_d);
  EXPECT_TRUE(p.model.temporal);
  EXPECT_EQ(p.model.color_mode, ColorMode::kLogHdr);
  for (auto [a, b] : {std::pair{&m.xyz, &p.model.xyz}, {&m.t, &p.model.t},
                      {&m.log_scales, &p.model.log_scales}, {&m.rot_left, &p.model.rot_left},
                      {&m.rot_right, &p.model.rot_right}, {&m.opacity_logit, &p.model.opacity_logit},
                      {&m.color_dc, &p.model.color_dc}, {&m.color_rest, &p.model.color_rest}}) {
    EXPECT_EQ(*a, *b);
  }
  EXPECT_EQ(p.hdr_offset, head.offset);
  EXPECT_EQ(p.comments.at("hdr4d-exposure-range"), (std::vector<double>{0.01, 4.0}));
  EXPECT_EQ(p.comments.at("hdr4d-hdr-head-log-scale"), (std::vector<double>{0.5}));
}

// The HDR slice read back as a static model renders the 4D model's HDR image at that time.
TEST(GaussianPly, HdrSliceRendersTheSameHdrImage) {
  testing::TempDir dir;
  const GaussianModel m = RandomModel(300, 2);
  const ExportDisplay display{nullptr, {0, -1, 0.0f}};
  const HdrPlyExtension hdr{0.01, 4.0, {}, nullptr};
  for (float time : {0.3f, 0.6f}) {
    ASSERT_GT(ExportSlicePly(m, time, 1.0f, dir / "s.ply", &display, &hdr), 50u);
    const GaussianPly p = ReadGaussianPly(dir / "s.ply");
    EXPECT_FALSE(p.model.temporal);
    EXPECT_EQ(p.model.color_mode, ColorMode::kLogHdr);
    EXPECT_EQ(p.comments.at("hdr4d-exposure-range"), (std::vector<double>{0.01, 4.0}));
    const std::vector<float> want = RenderHdr(m, time), got = RenderHdr(p.model, time);
    ASSERT_EQ(want.size(), got.size());
    double max_rel = 0, peak = 0;
    for (float v : want) peak = std::max(peak, double(v));
    for (std::size_t k = 0; k < want.size(); ++k)
      max_rel = std::max(max_rel, std::abs(double(want[k]) - got[k]) / peak);
    EXPECT_GT(peak, 0.0);
    EXPECT_LT(max_rel, 1e-4) << "time " << time;  // float rounding of the eigen-decomposition
  }
}

TEST(GaussianPly, LdrModelsRefuseTheHdrColumns) {
  testing::TempDir dir;
  GaussianModel m = RandomModel(5, 3);
  m.color_mode = ColorMode::kLdr;
  const HdrPlyExtension hdr;
  const std::string error = testing::ErrorOf([&] { ExportSlicePly(m, 0.5f, 1.0f, dir / "a.ply", nullptr, &hdr); });
  EXPECT_NE(error.find("LDR colours"), std::string::npos) << error;
}

TEST(GaussianPly, ReaderNamesTheFileAndTheProblem) {
  testing::TempDir dir;
  testing::WriteTextFile(dir / "a.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n");
  EXPECT_NE(testing::ErrorOf([&] { ReadGaussianPly(dir / "a.ply"); }).find("not binary_little_endian"),
            std::string::npos);
  testing::WriteTextFile(dir / "b.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nend_header\nabcd");
  const std::string short_body = testing::ErrorOf([&] { ReadGaussianPly(dir / "b.ply"); });
  EXPECT_NE(short_body.find("b.ply"), std::string::npos);
  EXPECT_NE(short_body.find("fewer than 2 vertices"), std::string::npos) << short_body;
  testing::WriteTextFile(dir / "c.txt", "hello");
  EXPECT_NE(testing::ErrorOf([&] { ReadGaussianPly(dir / "c.txt"); }).find("not a .ply"), std::string::npos);
}

TEST(ToneTables, LookUpIsLinearInLogHdrAndLogExposureAndHeldAtTheEnds) {
  ToneTables t;
  t.x0 = 0, t.x1 = 1, t.nodes = 2, t.time_indices = {0}, t.log_exposures = {0, 1};
  // value = x + 10 log_e in every channel
  t.values = {0, 0, 0, 1, 1, 1, 10, 10, 10, 11, 11, 11};
  EXPECT_FLOAT_EQ(LookUpToneTables(t, 0, 0.5f, 0.25f, 1), 5.25f);
  EXPECT_FLOAT_EQ(LookUpToneTables(t, 0, -3.0f, 2.0f, 0), 1.0f);
  EXPECT_FLOAT_EQ(LookUpToneTables(t, 0, 3.0f, -1.0f, 2), 10.0f);
}

}  // namespace
}  // namespace hdr4d::method
