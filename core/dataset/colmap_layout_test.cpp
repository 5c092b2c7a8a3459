#include "core/dataset/colmap_layout.h"

#include <gtest/gtest.h>

#include "core/geometry/colmap_model.h"
#include "core/image/image_io.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

namespace fs = std::filesystem;

// Four views in HDR-GS's synthetic layout: model names carry the _0 suffix.
void WriteHdrGsScene(const fs::path& root, const std::string& model = "PINHOLE") {
  ColmapModel m;
  m.cameras[1] = {1, model, 8, 6, model == "PINHOLE" ? std::vector<double>{10, 10, 4, 3}
                                                     : std::vector<double>{10, 4, 3, 0.1}};
  for (int v = 0; v < 4; ++v) {
    ColmapImage image;
    image.id = v + 1;
    image.camera_id = 1;
    image.name = "v" + std::to_string(v) + "_0.png";
    image.cam_from_world_translation = {0.1 * v, 0, 2};
    m.images[v + 1] = image;
    for (int k = 0; k < 5; ++k)
      WriteImage(root / "images" / ("v" + std::to_string(v) + "_" + std::to_string(k) + ".png"),
                 Image(8, 6, 3, Encoding::kSrgb, 0.5f));
    WriteImage(root / "exr" / ("v" + std::to_string(v) + ".exr"), Image(8, 6, 3));
  }
  WriteColmapModel(root / "sparse" / "0", m, ColmapFormat::kBinary);
}

TEST(HdrGsColmapLayout, LoadsWithTheHdrGsSplit) {
  testing::TempDir dir;
  WriteHdrGsScene(dir.path());
  const Dataset d = LoadDataset(dir.path());
  EXPECT_EQ(d.layout, "hdrgs-colmap");
  ASSERT_EQ(d.train.size(), 6u);  // views 0 and 2 at exposures 0.125, 2, 32
  ASSERT_EQ(d.test.size(), 10u);  // views 1 and 3 at all five
  EXPECT_EQ(d.train[1].exposure, 2.0);
  EXPECT_EQ(d.train[1].file_path, "images/v0_2.png");
  EXPECT_EQ(d.test[4].exposure, 32.0);
  EXPECT_EQ(*d.test[0].exr_file_path, "exr/v1.exr");
  // COLMAP's cam_from_world (OpenCV axes) comes back through the GL transform_matrix.
  Eigen::Matrix4d expected = Eigen::Matrix4d::Identity();
  expected.topRightCorner<3, 1>() = Eigen::Vector3d(0.1, 0, 2);
  EXPECT_TRUE(d.test[0].camera.CamFromWorldCv().isApprox(expected, 1e-12));
  EXPECT_EQ(d.train[0].camera.intrinsics.fx, 10);
}

TEST(HdrGsColmapLayout, ProblemsNameTheFile) {
  testing::TempDir dir;
  WriteHdrGsScene(dir / "a");
  fs::remove(dir / "a" / "images" / "v3_4.png");
  EXPECT_NE(testing::ErrorOf([&] { LoadDataset(dir / "a"); }).find("v3_4.png: view v3 exposure 4: image not found"),
            std::string::npos);
  WriteHdrGsScene(dir / "b", "SIMPLE_RADIAL");
  EXPECT_NE(testing::ErrorOf([&] { LoadDataset(dir / "b"); }).find("lens distortion"), std::string::npos);
  // The sweep of session 94: tangential distortion alone, and a focal length of zero, were read
  // as a pinhole camera.
  WriteHdrGsScene(dir / "c");
  ColmapModel m = ReadColmapModel(dir / "c" / "sparse" / "0");
  m.cameras[1] = {1, "OPENCV", 8, 6, {10, 10, 4, 3, 0, 0, 0.05, 0.05}};
  WriteColmapModel(dir / "c" / "sparse" / "0", m, ColmapFormat::kText);
  fs::remove(dir / "c" / "sparse" / "0" / "cameras.bin");
  fs::remove(dir / "c" / "sparse" / "0" / "images.bin");
  fs::remove(dir / "c" / "sparse" / "0" / "points3D.bin");
  EXPECT_NE(testing::ErrorOf([&] { LoadDataset(dir / "c"); }).find("lens distortion (OPENCV)"),
            std::string::npos);
  m.cameras[1] = {1, "PINHOLE", 8, 6, {0, 10, 4, 3}};
  WriteColmapModel(dir / "c" / "sparse" / "0", m, ColmapFormat::kText);
  EXPECT_NE(testing::ErrorOf([&] { LoadDataset(dir / "c"); }).find("camera 1: focal length fx=0"),
            std::string::npos);
}

}  // namespace
}  // namespace hdr4d
