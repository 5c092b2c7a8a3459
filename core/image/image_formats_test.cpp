// The formats OpenImageIO used to read for us, now each on its own library (image_formats.h):
// TIFF layouts, Radiance RGBE scanlines, exposure times from EXIF and EXR headers, damaged JPEGs.
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <gtest/gtest.h>
#include <tiffio.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "core/image/image_io.h"
#include "core/util/error.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

using testing::TempDir;
namespace fs = std::filesystem;

// A 5x3 TIFF of `samples` channels; sample (x, y, c) holds code (7x + 3y + 11c) % 251 scaled to
// the type; separate planes when `planar` is true.
void WriteTestTiff(const fs::path& path, int samples, int bits, bool is_float, bool planar,
                   double exposure = 0) {
  TIFF* tif = TIFFOpen(path.c_str(), "w");
  ASSERT_NE(tif, nullptr);
  const int w = 5, h = 3;
  TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, w);
  TIFFSetField(tif, TIFFTAG_IMAGELENGTH, h);
  TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, samples);
  TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, bits);
  TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT, is_float ? SAMPLEFORMAT_IEEEFP : SAMPLEFORMAT_UINT);
  TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, samples >= 3 ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK);
  TIFFSetField(tif, TIFFTAG_PLANARCONFIG, planar ? PLANARCONFIG_SEPARATE : PLANARCONFIG_CONTIG);
  if (samples == 4 || samples == 2) {
    const std::uint16_t extra = EXTRASAMPLE_UNASSALPHA;
    TIFFSetField(tif, TIFFTAG_EXTRASAMPLES, 1, &extra);
  }
  TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, 1);
  if (exposure > 0) TIFFSetField(tif, TIFFTAG_EXIFIFD, static_cast<toff_t>(0));
  const int bytes = bits / 8;
  for (int plane = 0; plane < (planar ? samples : 1); ++plane) {
    for (int y = 0; y < h; ++y) {
      std::vector<unsigned char> line(static_cast<std::size_t>(w) * (planar ? 1 : samples) * bytes);
      for (int x = 0; x < w; ++x) {
        for (int c = 0; c < (planar ? 1 : samples); ++c) {
          const int channel = planar ? plane : c;
          const int code = (7 * x + 3 * y + 11 * channel) % 251;
          const int index = x * (planar ? 1 : samples) + c;
          if (is_float) {
            const float v = code * 0.5f;
            std::memcpy(&line[4 * index], &v, 4);
          } else if (bits == 16) {
            const std::uint16_t v = static_cast<std::uint16_t>(code * 257);
            std::memcpy(&line[2 * index], &v, 2);
          } else {
            line[index] = static_cast<unsigned char>(code);
          }
        }
      }
      ASSERT_GE(TIFFWriteScanline(tif, line.data(), y, static_cast<std::uint16_t>(plane)), 0);
    }
  }
  if (exposure > 0) {
    // The EXIF directory is written after the image's, then linked from it.
    ASSERT_TRUE(TIFFWriteDirectory(tif));
    ASSERT_EQ(TIFFCreateEXIFDirectory(tif), 0);
    TIFFSetField(tif, EXIFTAG_EXPOSURETIME, exposure);
    std::uint64_t offset = 0;
    ASSERT_TRUE(TIFFWriteCustomDirectory(tif, &offset));
    ASSERT_TRUE(TIFFSetDirectory(tif, 0));
    TIFFSetField(tif, TIFFTAG_EXIFIFD, offset);
  }
  TIFFClose(tif);
}

float ExpectedTiffValue(int x, int y, int c, int bits, bool is_float) {
  const int code = (7 * x + 3 * y + 11 * c) % 251;
  if (is_float) return code * 0.5f;
  return bits == 16 ? code * 257 / 65535.0f : code / 255.0f;
}

TEST(ImageFormats, TiffSamplesOfEveryKindAndLayoutReadAsStored) {
  TempDir dir;
  struct Case { int samples, bits; bool is_float, planar; };
  for (const Case k : {Case{3, 8, false, false}, Case{4, 16, false, false}, Case{1, 32, true, false},
                       Case{3, 16, false, true}, Case{2, 8, false, false}}) {
    const fs::path path = dir / fmt::format("t{}_{}_{}_{}.tif", k.samples, k.bits, k.is_float,
                                            k.planar);
    WriteTestTiff(path, k.samples, k.bits, k.is_float, k.planar);
    const ImageSpecInfo spec = ReadImageSpec(path);
    EXPECT_EQ(spec.width, 5);
    EXPECT_EQ(spec.channels, k.samples);
    EXPECT_EQ(spec.linear, k.is_float);
    const Image image = ReadImage(path);
    ASSERT_EQ(image.width(), 5);
    ASSERT_EQ(image.height(), 3);
    ASSERT_EQ(image.channels(), k.samples);
    EXPECT_EQ(image.encoding(), k.is_float ? Encoding::kLinear : Encoding::kSrgb);
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 5; ++x)
        for (int c = 0; c < k.samples; ++c)
          ASSERT_FLOAT_EQ(image.at(x, y, c), ExpectedTiffValue(x, y, c, k.bits, k.is_float))
              << path << " " << x << "," << y << "," << c;
  }
}

// A 2x1 float EXR whose channels are named `names`; channel k holds k + 1 everywhere.
void WriteNamedExr(const fs::path& path, const std::vector<std::string>& names) {
  Imf::Header header(2, 1);
  std::vector<std::vector<float>> planes;
  for (std::size_t k = 0; k < names.size(); ++k) planes.emplace_back(2, float(k + 1));
  Imf::FrameBuffer buffer;
  for (std::size_t k = 0; k < names.size(); ++k) {
    header.channels().insert(names[k], Imf::Channel(Imf::FLOAT));
    buffer.insert(names[k], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(planes[k].data()),
                                       sizeof(float), 2 * sizeof(float)));
  }
  Imf::OutputFile file(path.c_str(), header);
  file.setFrameBuffer(buffer);
  file.writePixels(1);
}

// The value of each channel read at pixel (0, 0), in the image's order.
std::vector<float> FirstPixel(const Image& image) {
  std::vector<float> v;
  for (int c = 0; c < image.channels(); ++c) v.push_back(image.at(0, 0, c));
  return v;
}

// EXR stores channels sorted by name, so a layer prefix or lower case put B before G before R
// (and A first): the reader matches R, G, B, A by their last name part, any case.
TEST(ImageFormats, ExrColourChannelsAreFoundByNameWhateverTheirLayerOrCase) {
  TempDir dir;
  using V = std::vector<float>;
  WriteNamedExr(dir / "plain.exr", {"R", "G", "B"});
  EXPECT_EQ(FirstPixel(ReadImage(dir / "plain.exr")), (V{1, 2, 3}));
  WriteNamedExr(dir / "layer.exr", {"L.R", "L.G", "L.B"});
  EXPECT_EQ(FirstPixel(ReadImage(dir / "layer.exr")), (V{1, 2, 3}));
  WriteNamedExr(dir / "lower.exr", {"r", "g", "b", "a"});
  EXPECT_EQ(FirstPixel(ReadImage(dir / "lower.exr")), (V{1, 2, 3, 4}));
  // Blender's multilayer file: the Combined pass, not the other passes.
  WriteNamedExr(dir / "blender.exr", {"ViewLayer.Combined.R", "ViewLayer.Combined.G",
                                      "ViewLayer.Combined.B", "ViewLayer.Combined.A",
                                      "ViewLayer.Noisy.R", "ViewLayer.Noisy.G",
                                      "ViewLayer.Noisy.B", "ViewLayer.Depth.Z"});
  EXPECT_EQ(FirstPixel(ReadImage(dir / "blender.exr")), (V{1, 2, 3, 4}));
  EXPECT_EQ(ReadImageSpec(dir / "blender.exr").channels, 4);
  WriteNamedExr(dir / "grey.exr", {"depth"});
  EXPECT_EQ(FirstPixel(ReadImage(dir / "grey.exr")), (V{1}));
  // Refused, naming the file: two colour layers, neither Combined; channels of no colour.
  WriteNamedExr(dir / "two.exr", {"a.R", "a.G", "a.B", "b.R", "b.G", "b.B"});
  std::string e = testing::ErrorOf([&] { ReadImage(dir / "two.exr"); });
  EXPECT_NE(e.find("two.exr"), std::string::npos) << e;
  EXPECT_NE(e.find("several layers"), std::string::npos) << e;
  WriteNamedExr(dir / "uv.exr", {"U", "V"});
  for (const std::string& message : {testing::ErrorOf([&] { ReadImage(dir / "uv.exr"); }),
                                     testing::ErrorOf([&] { ReadImageSpec(dir / "uv.exr"); })}) {
    EXPECT_NE(message.find("uv.exr"), std::string::npos) << message;
    EXPECT_NE(message.find("no R, G, B or Y"), std::string::npos) << message;
    EXPECT_EQ(message.find("cannot read image"), std::string::npos) << message;  // said once
  }
}

TEST(ImageFormats, ExposureTimeFromTiffExifAndExrHeaderAndNoneFromPng) {
  TempDir dir;
  WriteTestTiff(dir / "e.tif", 3, 8, false, false, 0.125);
  ASSERT_EQ(ReadImage(dir / "e.tif").channels(), 3);
  EXPECT_DOUBLE_EQ(ReadExposureTime(dir / "e.tif").value_or(-1), 0.125);
  WriteTestTiff(dir / "none.tif", 3, 8, false, false);
  EXPECT_FALSE(ReadExposureTime(dir / "none.tif").has_value());

  Imf::Header header(2, 2);
  header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
  Imf::addExpTime(header, 0.5f);
  std::vector<float> y(4, 1.0f);
  Imf::FrameBuffer buffer;
  buffer.insert("Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(y.data()), 4, 8));
  {
    Imf::OutputFile file((dir / "t.exr").c_str(), header);
    file.setFrameBuffer(buffer);
    file.writePixels(2);
  }
  EXPECT_DOUBLE_EQ(ReadExposureTime(dir / "t.exr").value_or(-1), 0.5);
  EXPECT_EQ(ReadImage(dir / "t.exr").channels(), 1);

  WriteImage(dir / "p.png", Image(2, 2, 3, Encoding::kSrgb, 0.5f));
  EXPECT_FALSE(ReadExposureTime(dir / "p.png").has_value());
  EXPECT_THROW(ReadExposureTime(dir / "missing.jpg"), Error);
}

// A JPEG with an APP1 EXIF segment holding ExposureTime 1/250 s, as cameras write it: the EXIF
// block is a little TIFF whose first directory points to the EXIF directory.
std::string ExifSegment() {
  std::string tiff("II*\0\x08\0\0\0", 8);
  const auto u16 = [](int v) { return std::string{static_cast<char>(v & 255), static_cast<char>(v >> 8)}; };
  const auto u32 = [](unsigned v) {
    return std::string{static_cast<char>(v & 255), static_cast<char>((v >> 8) & 255),
                       static_cast<char>((v >> 16) & 255), static_cast<char>(v >> 24)};
  };
  // IFD0 at 8: one entry, ExifIFD (0x8769, LONG) -> 26; next IFD 0.
  tiff += u16(1) + u16(0x8769) + u16(4) + u32(1) + u32(26) + u32(0);
  // EXIF IFD at 26: ExposureTime (0x829a, RATIONAL) at 44; next 0. Rational 1/250 at 44.
  tiff += u16(1) + u16(0x829a) + u16(5) + u32(1) + u32(44) + u32(0);
  tiff += u32(1) + u32(250);
  const std::string body = std::string("Exif\0\0", 6) + tiff;
  const int length = static_cast<int>(body.size()) + 2;
  return std::string("\xff\xe1", 2) + static_cast<char>(length >> 8) +
         static_cast<char>(length & 255) + body;
}

TEST(ImageFormats, JpegExposureTimeFromItsExifSegment) {
  TempDir dir;
  WriteImage(dir / "plain.jpg", Image(8, 8, 3, Encoding::kSrgb, 0.25f));
  EXPECT_FALSE(ReadExposureTime(dir / "plain.jpg").has_value());
  std::ifstream in(dir / "plain.jpg", std::ios::binary);
  const std::string jpeg((std::istreambuf_iterator<char>(in)), {});
  std::ofstream(dir / "exif.jpg", std::ios::binary) << jpeg.substr(0, 2) + ExifSegment() + jpeg.substr(2);
  EXPECT_DOUBLE_EQ(ReadExposureTime(dir / "exif.jpg").value_or(-1), 1.0 / 250);
  EXPECT_NEAR(ReadImage(dir / "exif.jpg").at(3, 3, 1), 0.25f, 0.01f);
}

TEST(ImageFormats, TruncatedJpegIsRefusedNotPaddedWithGrey) {
  TempDir dir;
  Image image(64, 64, 3, Encoding::kSrgb);
  for (std::size_t i = 0; i < image.size(); ++i) image.values()[i] = (i * 37 % 101) / 100.0f;
  WriteImage(dir / "a.jpg", image);
  std::ifstream in(dir / "a.jpg", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  std::ofstream(dir / "cut.jpg", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  try {
    ReadImage(dir / "cut.jpg");
    FAIL() << "a truncated JPEG was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cut.jpg: cannot decode image"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(ReadImageSpec(dir / "cut.jpg").width, 64);  // the header is intact
}

// Radiance RGBE: (mantissa + 0.5) / 256 * 2^(exponent - 128) per channel.
TEST(ImageFormats, RadianceHdrReadsRunLengthAndFlatScanlines) {
  TempDir dir;
  const int w = 9;  // >= 8: run-length coded lines are allowed
  std::string file = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 9\n";
  // Line 0, run-length: each component one run of 9 (130 -> 2^(130-136) scale), except G literal.
  file += std::string{2, 2, 0, static_cast<char>(w)};
  file += std::string{static_cast<char>(128 + 9), static_cast<char>(100)};  // R: 9 x 100
  file += static_cast<char>(9);
  for (int x = 0; x < w; ++x) file += static_cast<char>(10 * x);  // G: literals
  file += std::string{static_cast<char>(128 + 9), static_cast<char>(0)};    // B: 9 x 0
  file += std::string{static_cast<char>(128 + 9), static_cast<char>(130)};  // E: 9 x 130
  // Line 1, flat: 9 pixels of (64, 128, 255, 129), the last one black (exponent 0).
  for (int x = 0; x < w; ++x)
    file += x == w - 1 ? std::string(4, '\0')
                       : std::string{64, static_cast<char>(128), static_cast<char>(255),
                                     static_cast<char>(129)};
  std::ofstream(dir / "a.hdr", std::ios::binary) << file;
  const Image image = ReadImage(dir / "a.hdr");
  ASSERT_EQ(image.width(), w);
  ASSERT_EQ(image.height(), 2);
  EXPECT_EQ(image.encoding(), Encoding::kLinear);
  const auto value = [](int m, int e) { return (m + 0.5f) * std::ldexp(1.0f, e - 136); };
  EXPECT_FLOAT_EQ(image.at(4, 0, 0), value(100, 130));
  EXPECT_FLOAT_EQ(image.at(4, 0, 1), value(40, 130));
  EXPECT_FLOAT_EQ(image.at(4, 0, 2), value(0, 130));
  EXPECT_FLOAT_EQ(image.at(2, 1, 2), value(255, 129));
  EXPECT_EQ(image.at(w - 1, 1, 0), 0.0f);

  std::ofstream(dir / "cut.hdr", std::ios::binary) << file.substr(0, file.size() - 5);
  EXPECT_THROW(ReadImage(dir / "cut.hdr"), Error);
  std::ofstream(dir / "rot.hdr", std::ios::binary) << "#?RADIANCE\n\n+X 9 -Y 2\n";
  try {
    ReadImage(dir / "rot.hdr");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("orientation"), std::string::npos) << e.what();
  }
}

TEST(ImageFormats, UnknownFormatNamesWhatIsRead) {
  TempDir dir;
  std::ofstream(dir / "a.bmp", std::ios::binary) << "BM" << std::string(60, '\0');
  try {
    ReadImage(dir / "a.bmp");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("a.bmp: cannot read image: not an EXR, PNG, JPEG, TIFF"),
              std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(IsImagePath("x/Y.TIFF"));
  EXPECT_FALSE(IsImagePath("x/y.bmp"));
}

}  // namespace
}  // namespace hdr4d
