#include "core/geometry/ply.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <string>

#include "core/util/error.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

using testing::TempDir;
using testing::WriteTextFile;

PointCloud SampleCloud(bool colors, bool times) {
  PointCloud cloud;
  for (int i = 0; i < 7; ++i) {
    cloud.positions.emplace_back(0.1f * i - 0.3f, 1.5f * i, -2.25f + i * 1e-3f);
    if (colors) cloud.colors.emplace_back(i / 6.0f, 1.0f - i / 6.0f, 0.5f);
    if (times) cloud.times.push_back(0.125f * i);
  }
  return cloud;
}

void ExpectSameCloud(const PointCloud& a, const PointCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.colors.size(), b.colors.size());
  ASSERT_EQ(a.times.size(), b.times.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a.positions[i], b.positions[i]) << i;  // float positions are stored exactly
    if (a.has_colors()) {
      EXPECT_LE((a.colors[i] - b.colors[i]).cwiseAbs().maxCoeff(), 0.5f / 255 + 1e-6f)
          << i;  // 8 bits
    }
    if (a.has_times()) {
      EXPECT_EQ(a.times[i], b.times[i]) << i;
    }
  }
}

// Appends a little-endian value.
template <typename T>
void Put(std::string& s, T v) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &v, sizeof(T));
  s.append(bytes, sizeof(T));
}

// The error ReadPly gives for `path`, or "" when it reads the file.
std::string PlyError(const std::filesystem::path& path) {
  return testing::ErrorOf([&] { ReadPly(path); });
}

TEST(Ply, BinaryRoundTripWithColorsAndTimes) {
  TempDir dir;
  const PointCloud cloud = SampleCloud(true, true);
  WritePly(dir / "a.ply", cloud);
  const std::string text = testing::ReadTextFile(dir / "a.ply");
  EXPECT_NE(text.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(text.find("property uchar red"), std::string::npos);
  EXPECT_NE(text.find("property float time"), std::string::npos);
  // Header + 7 * (3 floats + 3 bytes + 1 float).
  EXPECT_EQ(text.size() - text.find("end_header\n") - 11, 7u * 19);
  const PointCloud back = ReadPly(dir / "a.ply");
  ExpectSameCloud(cloud, back);
  EXPECT_FLOAT_EQ(back.colors[6][0], 1.0f);
  EXPECT_FLOAT_EQ(back.colors[3][2], 128.0f / 255.0f);  // 0.5 -> 128
}

TEST(Ply, BinaryRoundTripPositionsOnly) {
  TempDir dir;
  const PointCloud cloud = SampleCloud(false, false);
  WritePly(dir / "a.ply", cloud);
  const PointCloud back = ReadPly(dir / "a.ply");
  ExpectSameCloud(cloud, back);
  EXPECT_FALSE(back.has_colors());
  EXPECT_FALSE(back.has_times());
}

TEST(Ply, AsciiRoundTrip) {
  TempDir dir;
  const PointCloud cloud = SampleCloud(true, true);
  WritePly(dir / "a.ply", cloud, {.format = PlyFormat::kAscii});
  EXPECT_NE(testing::ReadTextFile(dir / "a.ply").find("format ascii 1.0"), std::string::npos);
  ExpectSameCloud(cloud, ReadPly(dir / "a.ply"));
}

TEST(Ply, EmptyCloudRoundTrip) {
  TempDir dir;
  WritePly(dir / "e.ply", PointCloud{});
  EXPECT_EQ(ReadPly(dir / "e.ply").size(), 0u);
}

TEST(Ply, AsciiWithDoublesFloatColorsExtraPropertiesAndElements) {
  TempDir dir;
  WriteTextFile(dir / "a.ply",
                "ply\r\n"
                "format ascii 1.0\r\n"
                "comment made by hand\r\n"
                "element camera 1\r\n"
                "property float fov\r\n"
                "property list uchar int ids\r\n"
                "element vertex 2\r\n"
                "property double x\r\n"
                "property double y\r\n"
                "property float nx\r\n"
                "property double z\r\n"
                "property float red\r\nproperty float green\r\nproperty float blue\r\n"
                "property float time\r\n"
                "element face 1\r\n"
                "property list uchar int vertex_indices\r\n"
                "end_header\r\n"
                "0.7 3 1 2 3\r\n"
                "1.5 -2 9 3.25 0.25 0.5 1 0.75\r\n"
                "4 5 9 6 0 0 0 1e-3\r\n"
                "3 0 1 2\r\n");
  const PointCloud cloud = ReadPly(dir / "a.ply");
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.positions[0], Eigen::Vector3f(1.5f, -2.0f, 3.25f));
  EXPECT_EQ(cloud.positions[1], Eigen::Vector3f(4, 5, 6));
  EXPECT_EQ(cloud.colors[0], Eigen::Vector3f(0.25f, 0.5f, 1.0f));
  EXPECT_FLOAT_EQ(cloud.times[0], 0.75f);
  EXPECT_FLOAT_EQ(cloud.times[1], 1e-3f);
}

TEST(Ply, BinarySkipsOtherPropertiesAndElementsByTypeSize) {
  // A 3DGS-style vertex (normals, SH, opacity of every width) after an element with a list.
  TempDir dir;
  std::string s =
      "ply\nformat binary_little_endian 1.0\n"
      "element meta 2\nproperty list uchar ushort ids\nproperty double weight\n"
      "element vertex 2\n"
      "property char a\nproperty float x\nproperty short b\nproperty double y\n"
      "property ushort c\nproperty float32 z\nproperty int d\nproperty uchar red\n"
      "property uint e\nproperty uint8 green\nproperty float64 f\nproperty uchar blue\n"
      "property int8 g\nproperty float time\nproperty uint16 h\n"
      "element face 1\nproperty list uchar int vertex_indices\n"
      "end_header\n";
  // meta: item 0 with 2 ids, item 1 with 0 ids.
  Put<std::uint8_t>(s, 2), Put<std::uint16_t>(s, 7), Put<std::uint16_t>(s, 8), Put<double>(s, 0.5);
  Put<std::uint8_t>(s, 0), Put<double>(s, 1.5);
  for (int i = 0; i < 2; ++i) {
    Put<std::int8_t>(s, -1), Put<float>(s, 1.0f + i), Put<std::int16_t>(s, -2);
    Put<double>(s, 2.0 + i), Put<std::uint16_t>(s, 3), Put<float>(s, 3.0f + i);
    Put<std::int32_t>(s, -4), Put<std::uint8_t>(s, 255), Put<std::uint32_t>(s, 5);
    Put<std::uint8_t>(s, 51), Put<double>(s, 6.0), Put<std::uint8_t>(s, 0);
    Put<std::int8_t>(s, 7), Put<float>(s, 0.25f * (i + 1)), Put<std::uint16_t>(s, 8);
  }
  Put<std::uint8_t>(s, 3), Put<std::int32_t>(s, 0), Put<std::int32_t>(s, 1),
      Put<std::int32_t>(s, 0);
  WriteTextFile(dir / "b.ply", s);
  const PointCloud cloud = ReadPly(dir / "b.ply");
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.positions[0], Eigen::Vector3f(1, 2, 3));
  EXPECT_EQ(cloud.positions[1], Eigen::Vector3f(2, 3, 4));
  EXPECT_EQ(cloud.colors[1], Eigen::Vector3f(1.0f, 0.2f, 0.0f));
  EXPECT_FLOAT_EQ(cloud.times[0], 0.25f);
  EXPECT_FLOAT_EQ(cloud.times[1], 0.5f);
}

TEST(Ply, Uint16ColorsScaleByTheirMaximum) {
  TempDir dir;
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
      "property float x\nproperty float y\nproperty float z\n"
      "property ushort red\nproperty ushort green\nproperty ushort blue\nend_header\n";
  Put<float>(s, 0), Put<float>(s, 0), Put<float>(s, 0);
  Put<std::uint16_t>(s, 65535), Put<std::uint16_t>(s, 0), Put<std::uint16_t>(s, 13107);
  WriteTextFile(dir / "c.ply", s);
  const PointCloud cloud = ReadPly(dir / "c.ply");
  EXPECT_FLOAT_EQ(cloud.colors[0][0], 1.0f);
  EXPECT_FLOAT_EQ(cloud.colors[0][2], 0.2f);
}

TEST(Ply, TruncatedBinaryDataNamesTheFile) {
  TempDir dir;
  WritePly(dir / "t.ply", SampleCloud(true, false));
  std::string text = testing::ReadTextFile(dir / "t.ply");
  text.resize(text.size() - 5);
  WriteTextFile(dir / "t.ply", text);
  const std::string error = PlyError(dir / "t.ply");
  EXPECT_NE(error.find((dir / "t.ply").string()), std::string::npos) << error;
  EXPECT_NE(error.find("truncated"), std::string::npos) << error;
  EXPECT_NE(error.find("declares 7 vertices, the file holds 6"), std::string::npos) << error;
}

TEST(Ply, TruncatedAsciiData) {
  TempDir dir;
  WriteTextFile(dir / "t.ply",
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                "property float z\nend_header\n1 2 3\n4 5 6\n7 8\n");
  const std::string error = PlyError(dir / "t.ply");
  EXPECT_NE(error.find("truncated"), std::string::npos) << error;
  EXPECT_NE(error.find("holds 2"), std::string::npos) << error;
}

TEST(Ply, TruncatedElementBeforeVertex) {
  TempDir dir;
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement extra 100\nproperty double w\n"
      "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  Put<double>(s, 1.0);
  WriteTextFile(dir / "t.ply", s);
  EXPECT_NE(PlyError(dir / "t.ply").find("truncated PLY data in element 'extra'"),
            std::string::npos);
}

TEST(Ply, NanCoordinateIsAnError) {
  TempDir dir;
  WriteTextFile(dir / "n.ply",
                "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                "property float z\nend_header\n1 2 3\n4 nan 6\n");
  const std::string error = PlyError(dir / "n.ply");
  EXPECT_NE(error.find((dir / "n.ply").string()), std::string::npos) << error;
  EXPECT_NE(error.find("vertex 1 has a non-finite coordinate"), std::string::npos) << error;

  PointCloud cloud = SampleCloud(false, false);
  cloud.positions[4].y() = std::nanf("");
  WritePly(dir / "b.ply", cloud);
  EXPECT_NE(PlyError(dir / "b.ply").find("vertex 4 has a non-finite coordinate"),
            std::string::npos);
}

TEST(Ply, NonFiniteTimeIsAnError) {
  TempDir dir;
  PointCloud cloud = SampleCloud(false, true);
  cloud.times[2] = INFINITY;
  WritePly(dir / "t.ply", cloud);
  EXPECT_NE(PlyError(dir / "t.ply").find("vertex 2 has a non-finite time"), std::string::npos);
}

TEST(Ply, MissingFile) {
  TempDir dir;
  const std::string error = PlyError(dir / "none.ply");
  EXPECT_NE(error.find((dir / "none.ply").string() + ": file not found"), std::string::npos)
      << error;
}

struct BadHeaderCase {
  const char* text;
  const char* expected;
};

TEST(Ply, BadHeaders) {
  const BadHeaderCase cases[] = {
      {"plx\nformat ascii 1.0\nend_header\n", "does not start with 'ply'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "no end_header"},
      {"ply\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
       "no format line"},
      {"ply\nformat binary_big_endian 1.0\nend_header\n",
       "unsupported PLY format binary_big_endian"},
      {"ply\nformat utf8 1.0\nend_header\n", "unknown format"},
      {"ply\nformat ascii 1.0\nelement vertex -3\nend_header\n", "malformed element line"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty half x\nend_header\n",
       "unknown property type 'half'"},
      {"ply\nformat ascii 1.0\nproperty float x\nend_header\n", "property before any element"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n",
       "lacks x, y or z"},
      {"ply\nformat ascii 1.0\nelement face 1\nend_header\n", "no vertex element"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
       "property float z\nproperty list uchar float normals\nend_header\n",
       "unsupported list property 'normals'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
       "property float z\nproperty uchar red\nend_header\n",
       "only some of red, green, blue"},
      {"ply\nformat ascii 1.0\nbanana\nend_header\n", "unknown keyword 'banana'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n1 2 three\n",
       "bad number 'three'"},
  };
  TempDir dir;
  for (const BadHeaderCase& c : cases) {
    WriteTextFile(dir / "h.ply", c.text);
    const std::string error = PlyError(dir / "h.ply");
    EXPECT_NE(error.find((dir / "h.ply").string()), std::string::npos) << c.text;
    EXPECT_NE(error.find(c.expected), std::string::npos) << c.text << " -> " << error;
  }
}

TEST(Ply, WriterRejectsMismatchedAttributes) {
  TempDir dir;
  PointCloud cloud = SampleCloud(true, true);
  cloud.colors.pop_back();
  EXPECT_THROW(WritePly(dir / "x.ply", cloud), Error);
  cloud = SampleCloud(false, true);
  cloud.times.push_back(1.0f);
  EXPECT_THROW(WritePly(dir / "x.ply", cloud), Error);
  EXPECT_FALSE(std::filesystem::exists(dir / "x.ply"));
}

TEST(Ply, WriterClampsColors) {
  TempDir dir;
  PointCloud cloud;
  cloud.positions = {Eigen::Vector3f(0, 0, 0)};
  cloud.colors = {Eigen::Vector3f(-1.0f, 2.0f, std::nanf(""))};
  WritePly(dir / "c.ply", cloud);
  EXPECT_EQ(ReadPly(dir / "c.ply").colors[0], Eigen::Vector3f(0, 1, 0));
}

}  // namespace
}  // namespace hdr4d
