#include "core/geometry/colmap_model.h"

#include <gtest/gtest.h>

#include <cmath>

#include <fstream>

#include "tests/testing.h"

namespace hdr4d {
namespace {

ColmapModel SmallModel() {
  ColmapModel m;
  m.cameras[1] = {1, "SIMPLE_RADIAL", 640, 480, {500.0, 320.0, 240.0, -0.05}};
  m.cameras[2] = {2, "PINHOLE", 320, 200, {300.0, 310.0, 160.5, 99.5}};
  ColmapImage a;
  a.id = 3;
  a.camera_id = 1;
  a.name = "cam0/img 0.jpg";  // a space in the name must survive the text format
  a.cam_from_world_rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  a.cam_from_world_translation = {0.1, -0.2, 1.5};
  a.points2d = {{10.25, 20.5}, {30, 40}};
  a.point3d_ids = {7, -1};
  ColmapImage b;
  b.id = 4;
  b.camera_id = 2;
  b.name = "cam1.png";  // no 2D points: an empty second line in images.txt
  m.images[3] = a;
  m.images[4] = b;
  ColmapPoint p;
  p.id = 7;
  p.xyz = {1, 2, 3};
  p.rgb = {1.0f, 0.0f, 128 / 255.0f};
  p.error = 0.75;
  p.track = {{3, 0}};
  m.points[7] = p;
  return m;
}

void ExpectSame(const ColmapModel& a, const ColmapModel& b) {
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (const auto& [id, c] : a.cameras) {
    const auto& d = b.cameras.at(id);
    EXPECT_EQ(c.model, d.model);
    EXPECT_EQ(c.width, d.width);
    EXPECT_EQ(c.height, d.height);
    EXPECT_EQ(c.params, d.params);
  }
  ASSERT_EQ(a.images.size(), b.images.size());
  for (const auto& [id, im] : a.images) {
    const auto& jm = b.images.at(id);
    EXPECT_EQ(im.name, jm.name);
    EXPECT_EQ(im.camera_id, jm.camera_id);
    EXPECT_TRUE(im.CamFromWorldCv().isApprox(jm.CamFromWorldCv(), 1e-12));
    EXPECT_EQ(im.points2d, jm.points2d);
    EXPECT_EQ(im.point3d_ids, jm.point3d_ids);
  }
  ASSERT_EQ(a.points.size(), b.points.size());
  for (const auto& [id, p] : a.points) {
    const auto& q = b.points.at(id);
    EXPECT_EQ(p.xyz, q.xyz);
    EXPECT_TRUE(p.rgb.isApprox(q.rgb, 1e-6f));
    EXPECT_EQ(p.error, q.error);
    EXPECT_EQ(p.track, q.track);
  }
}

TEST(ColmapModel, BinaryAndTextRoundTrip) {
  testing::TempDir dir;
  const ColmapModel m = SmallModel();
  WriteColmapModel(dir / "bin", m, ColmapFormat::kBinary);
  WriteColmapModel(dir / "txt", m, ColmapFormat::kText);
  ExpectSame(m, ReadColmapModel(dir / "bin"));
  ExpectSame(m, ReadColmapModel(dir / "txt"));
}

TEST(ColmapModel, IntrinsicsAndDistortion) {
  const ColmapModel m = SmallModel();
  const PinholeIntrinsics k = m.cameras.at(1).Pinhole();
  EXPECT_EQ(k.fx, 500);
  EXPECT_EQ(k.fy, 500);
  EXPECT_EQ(k.cx, 320);
  EXPECT_EQ(m.cameras.at(1).Radial().x(), -0.05);
  EXPECT_EQ(m.cameras.at(2).Pinhole().fy, 310);
  ColmapCamera fisheye{5, "OPENCV_FISHEYE", 10, 10, std::vector<double>(8, 1.0)};
  EXPECT_NE(testing::ErrorOf([&] { fisheye.Pinhole(); }).find("OPENCV_FISHEYE"), std::string::npos);
}

TEST(ColmapModel, ErrorsNameTheFile) {
  testing::TempDir dir;
  WriteColmapModel(dir / "m", SmallModel(), ColmapFormat::kBinary);
  std::filesystem::remove(dir / "m" / "points3D.bin");
  EXPECT_NE(testing::ErrorOf([&] { ReadColmapModel(dir / "m"); }).find("points3D.bin: file not found"),
            std::string::npos);
  // Truncated images.bin.
  WriteColmapModel(dir / "t", SmallModel(), ColmapFormat::kBinary);
  std::filesystem::resize_file(dir / "t" / "images.bin", 30);
  EXPECT_NE(testing::ErrorOf([&] { ReadColmapModel(dir / "t"); }).find("images.bin: truncated"),
            std::string::npos);
  // An image naming a camera that is not there.
  ColmapModel bad = SmallModel();
  bad.images[3].camera_id = 9;
  WriteColmapModel(dir / "r", bad, ColmapFormat::kText);
  EXPECT_NE(testing::ErrorOf([&] { ReadColmapModel(dir / "r"); }).find("names camera 9"),
            std::string::npos);
  // A wrong parameter count in text.
  testing::WriteTextFile(dir / "r" / "cameras.txt", "1 PINHOLE 10 10 1 2 3\n");
  EXPECT_NE(testing::ErrorOf([&] { ReadColmapModel(dir / "r"); }).find("needs 4 parameters"),
            std::string::npos);
  EXPECT_NE(testing::ErrorOf([&] { FindColmapModelFolder(dir.path()); }).find("no COLMAP sparse model"),
            std::string::npos);
  EXPECT_EQ(FindColmapModelFolder(dir / "t"), dir / "t");
}

// The sweep of session 94: a zero quaternion became the identity rotation, and NaN poses and
// parameters were read without a word; both formats now refuse them, naming file and place.
void ZeroQuaternion(ColmapModel* m) {
  m->images.begin()->second.cam_from_world_rotation.coeffs().setZero();
}
void InfiniteQuaternion(ColmapModel* m) {
  m->images.begin()->second.cam_from_world_rotation.x() = INFINITY;
}
void NanTranslation(ColmapModel* m) {
  m->images.begin()->second.cam_from_world_translation.y() = NAN;
}
void NanFocalLength(ColmapModel* m) { m->cameras.begin()->second.params[0] = NAN; }

TEST(ColmapModel, PosesAndParametersThatAreNoneAreRefused) {
  testing::TempDir dir;
  struct Case {
    const char* name;
    void (*change)(ColmapModel*);
    const char* problem;
    bool text;  // also as text (a text model cannot hold a NaN parameter: "cannot read")
  };
  const Case cases[] = {{"zero_q", ZeroQuaternion, "is not a rotation", true},
                        {"inf_q", InfiniteQuaternion, "is not a rotation", false},
                        {"nan_t", NanTranslation, "the translation is not finite", false},
                        {"nan_f", NanFocalLength, "camera 1: parameter 0 is nan", false}};
  for (const Case& c : cases) {
    for (ColmapFormat format : {ColmapFormat::kBinary, ColmapFormat::kText}) {
      if (format == ColmapFormat::kText && !c.text) continue;
      ColmapModel m = SmallModel();
      c.change(&m);
      const std::filesystem::path folder =
          dir / (std::string(c.name) + (format == ColmapFormat::kText ? "_txt" : "_bin"));
      WriteColmapModel(folder, m, format);
      const std::string error = testing::ErrorOf([&] { ReadColmapModel(folder); });
      EXPECT_NE(error.find(c.problem), std::string::npos) << folder << ": " << error;
      EXPECT_NE(error.find(folder.string()), std::string::npos) << error;
    }
  }
}

}  // namespace
}  // namespace hdr4d
