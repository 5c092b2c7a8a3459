#include "core/image/image_io.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/util/error.h"
#include "core/image/png_structure.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

using testing::RandomImage;
using testing::TempDir;

TEST(ImageIo, ExrFloatRoundTripIsExact) {
  TempDir dir;
  Image image = RandomImage(17, 9, 3, 1, -5.0f, 1e6f);
  image.at(0, 0, 0) = 1e-7f;
  WriteImage(dir / "a.exr", image, {.format = PixelFormat::kFloat});
  const Image back = ReadImage(dir / "a.exr");
  ASSERT_TRUE(back.SameShape(image));
  EXPECT_EQ(back.encoding(), Encoding::kLinear);
  for (std::size_t i = 0; i < image.size(); ++i)
    ASSERT_EQ(back.values()[i], image.values()[i]) << i;
}

TEST(ImageIo, ExrHalfRoundTripWithinHalfPrecision) {
  TempDir dir;
  const Image image = RandomImage(8, 8, 4, 2, 0.0f, 1000.0f);
  WriteImage(dir / "h.exr", image);  // half by default
  const Image back = ReadImage(dir / "h.exr");
  ASSERT_TRUE(back.SameShape(image));
  for (std::size_t i = 0; i < image.size(); ++i) {
    EXPECT_NEAR(back.values()[i], image.values()[i], std::abs(image.values()[i]) * 1e-3 + 1e-6);
  }
}

TEST(ImageIo, Png8RoundTripIsExactOnCodes) {
  TempDir dir;
  Image image(5, 4, 3, Encoding::kSrgb);
  for (std::size_t i = 0; i < image.size(); ++i)
    image.values()[i] = static_cast<float>(i * 7 % 256) / 255.0f;
  WriteImage(dir / "a.png", image);
  const Image back = ReadImage(dir / "a.png");
  ASSERT_TRUE(back.SameShape(image));
  EXPECT_EQ(back.encoding(), Encoding::kSrgb);
  for (std::size_t i = 0; i < image.size(); ++i)
    EXPECT_FLOAT_EQ(back.values()[i], image.values()[i]);
}

TEST(ImageIo, Png16RoundTripIsExactOnCodes) {
  TempDir dir;
  Image image(6, 3, 1, Encoding::kSrgb);
  for (std::size_t i = 0; i < image.size(); ++i)
    image.values()[i] = static_cast<float>(i * 3001 % 65536) / 65535.0f;
  WriteImage(dir / "a.png", image, {.format = PixelFormat::kUint16});
  const Image back = ReadImage(dir / "a.png");
  ASSERT_TRUE(back.SameShape(image));
  for (std::size_t i = 0; i < image.size(); ++i)
    EXPECT_NEAR(back.values()[i], image.values()[i], 1e-7);
}

TEST(ImageIo, PngClampsOutOfRangeValues) {
  TempDir dir;
  Image image(2, 1, 1, Encoding::kSrgb);
  image.values() = {-0.5f, 7.0f};
  WriteImage(dir / "c.png", image);
  const Image back = ReadImage(dir / "c.png");
  EXPECT_EQ(back.values()[0], 0.0f);
  EXPECT_EQ(back.values()[1], 1.0f);
}

TEST(ImageIo, JpegLoadsCloseToWhatWasWritten) {
  TempDir dir;
  Image image(32, 32, 3, Encoding::kSrgb, 0.5f);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) image.at(x, y, 0) = x / 31.0f;
  WriteImage(dir / "a.jpg", image);
  const Image back = ReadImage(dir / "a.jpg");
  ASSERT_TRUE(back.SameShape(image));
  double err = 0;
  for (std::size_t i = 0; i < image.size(); ++i)
    err += std::abs(back.values()[i] - image.values()[i]);
  EXPECT_LT(err / image.size(), 0.02);
}

TEST(ImageIo, MissingFileNamesTheFile) {
  TempDir dir;
  try {
    ReadImage(dir / "nope.png");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("nope.png"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("not found"), std::string::npos);
  }
}

TEST(ImageIo, CorruptFileIsAnError) {
  TempDir dir;
  testing::WriteTextFile(dir / "bad.png", "this is not a png");
  EXPECT_THROW(ReadImage(dir / "bad.png"), Error);
  // A PNG cut in half: the header reads, the pixels do not.
  const Image image = RandomImage(64, 64, 3, 3, 0, 1, Encoding::kSrgb);
  WriteImage(dir / "full.png", image);
  const std::string bytes = testing::ReadTextFile(dir / "full.png");
  testing::WriteTextFile(dir / "cut.png", bytes.substr(0, bytes.size() / 2));
  try {
    ReadImage(dir / "cut.png");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cut.png"), std::string::npos) << e.what();
  }
}

// Issue 11, case 13: libpng printed "libpng error: ..." and OpenImageIO "PNG library error" on
// stderr around hdr4d's own line. Broken PNGs are now found by their chunk structure before
// libpng reads them, so stderr stays silent and the message says what is wrong.
TEST(ImageIo, BrokenPngsAreReportedWithoutLibraryChatter) {
  TempDir dir;
  WriteImage(dir / "full.png", RandomImage(64, 64, 3, 3, 0, 1, Encoding::kSrgb));
  const std::string bytes = testing::ReadTextFile(dir / "full.png");
  testing::WriteTextFile(dir / "cut.png", bytes.substr(0, bytes.size() - 20));
  testing::WriteTextFile(dir / "head.png", bytes.substr(0, 20));
  std::string flipped = bytes;
  flipped[bytes.size() / 2] = static_cast<char>(flipped[bytes.size() / 2] ^ 0x40);
  testing::WriteTextFile(dir / "flip.png", flipped);
  struct Case {
    const char* name;
    const char* problem;
  };
  for (const Case& c : {Case{"cut.png", "truncated PNG: it ends inside chunk"},
                        Case{"head.png", "truncated PNG: it ends inside chunk IHDR"},
                        Case{"flip.png", "fails its CRC check"}}) {
    // stderr to a file for the duration of the read.
    const std::string log = (dir / "stderr.txt").string();
    std::fflush(stderr);
    const int saved = dup(2);
    FILE* f = std::fopen(log.c_str(), "w");
    dup2(fileno(f), 2);
    const std::string error = testing::ErrorOf([&] { ReadImage(dir / c.name); });
    const std::string header_error = testing::ErrorOf([&] { ReadImageSpec(dir / c.name); });
    std::fflush(stderr);
    dup2(saved, 2);
    close(saved);
    std::fclose(f);
    EXPECT_NE(error.find(std::string(c.name) + ": cannot read image: "), std::string::npos)
        << error;
    EXPECT_NE(error.find(c.problem), std::string::npos) << error;
    EXPECT_EQ(testing::ReadTextFile(log), "") << c.name;
    // Reading the header needs only the signature and IHDR.
    EXPECT_EQ(header_error.empty(), std::string(c.name) != "head.png") << header_error;
  }
  EXPECT_EQ(PngStructureProblem(dir / "full.png", true), "");
}

// An image this process has no memory for is an error naming the file, not "std::bad_alloc":
// read in a child whose address space is capped 64 MB above what it uses already.
TEST(ImageIo, AnImageBeyondTheMemoryLeftNamesTheFile) {
  TempDir dir;
  WriteImage(dir / "big.png", Image(4096, 4096, 1, Encoding::kSrgb, 0.5f));  // 64 MB of floats
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    close(fds[0]);
    long pages = 0;
    if (FILE* statm = std::fopen("/proc/self/statm", "r")) {
      if (std::fscanf(statm, "%ld", &pages) != 1) pages = 0;
      std::fclose(statm);
    }
    const rlim_t cap = static_cast<rlim_t>(pages) * sysconf(_SC_PAGESIZE) + (64 << 20);
    const rlimit limit{cap, cap};
    std::string message = "no limit";
    if (pages > 0 && setrlimit(RLIMIT_AS, &limit) == 0)
      message = testing::ErrorOf([&] { ReadImage(dir / "big.png"); });
    if (write(fds[1], message.data(), message.size()) < 0) _exit(2);
    _exit(0);
  }
  close(fds[1]);
  std::string message;
  char buffer[512];
  for (ssize_t n; (n = read(fds[0], buffer, sizeof buffer)) > 0;) message.append(buffer, n);
  close(fds[0]);
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  EXPECT_NE(message.find("big.png: cannot read image: not enough memory for 4096x4096"),
            std::string::npos) << message;
}

// The sweep of session 94: a small PNG whose header claims 30000x30000 RGBA16 (7.2 GB decoded)
// made ReadImage ask for the buffer and end in "std::bad_alloc", naming no file.
TEST(ImageIo, PngHeaderClaimingMorePixelsThanItsBytesCanHoldIsRefused) {
  TempDir dir;
  WriteImage(dir / "small.png", RandomImage(16, 16, 4, 5, 0, 1, Encoding::kSrgb),
             {.format = PixelFormat::kUint16});
  std::string bytes = testing::ReadTextFile(dir / "small.png");
  ASSERT_EQ(bytes.substr(12, 4), "IHDR");
  for (int k = 0; k < 2; ++k) {  // width and height, big-endian
    const std::uint32_t v = 30000;
    for (int b = 0; b < 4; ++b) bytes[16 + 4 * k + b] = static_cast<char>(v >> (24 - 8 * b));
  }
  const std::uint32_t crc = Crc32(bytes.data() + 12, 17);  // chunk type and data
  for (int b = 0; b < 4; ++b) bytes[29 + b] = static_cast<char>(crc >> (24 - 8 * b));
  testing::WriteTextFile(dir / "huge.png", bytes);
  EXPECT_EQ(ReadImageSpec(dir / "huge.png").width, 30000);  // the header itself is well formed
  const std::string error = testing::ErrorOf([&] { ReadImage(dir / "huge.png"); });
  EXPECT_NE(error.find("huge.png: cannot read image: its header claims 30000x30000"),
            std::string::npos) << error;
  EXPECT_NE(error.find("the file is damaged"), std::string::npos) << error;
}

TEST(ImageIo, NonFinitePixelIsRejectedWithItsPosition) {
  TempDir dir;
  Image image(4, 3, 3, Encoding::kLinear, 1.0f);
  image.at(2, 1, 1) = std::numeric_limits<float>::quiet_NaN();
  WriteImage(dir / "nan.exr", image, {.format = PixelFormat::kFloat});
  try {
    ReadImage(dir / "nan.exr");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("nan.exr"), std::string::npos) << what;
    EXPECT_NE(what.find("x=2, y=1"), std::string::npos) << what;
  }
  image.at(2, 1, 1) = std::numeric_limits<float>::infinity();
  WriteImage(dir / "inf.exr", image, {.format = PixelFormat::kFloat});
  EXPECT_THROW(ReadImage(dir / "inf.exr"), Error);
  EXPECT_NO_THROW(ReadImage(dir / "inf.exr", {.require_finite = false}));
}

TEST(ImageIo, WriteThatFailsHalfwayKeepsTheOldFile) {
  // A file-size limit makes the write fail after some bytes (as a full disk would), and works
  // for root too, unlike a read-only folder.
  TempDir dir;
  const Image first(4, 4, 3, Encoding::kSrgb, 0.25f);
  WriteImage(dir / "keep.exr", first);
  const std::string before = testing::ReadTextFile(dir / "keep.exr");
  rlimit old_limit{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);  // get EFBIG instead of a signal
  rlimit small = old_limit;
  small.rlim_cur = 4096;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  std::string error;
  try {
    WriteImage(dir / "keep.exr", RandomImage(256, 256, 3, 9, 0, 1),
               {.format = PixelFormat::kFloat});
  } catch (const Error& e) {
    error = e.what();
  }
  setrlimit(RLIMIT_FSIZE, &old_limit);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_NE(error.find((dir / "keep.exr").string()), std::string::npos) << error;
  EXPECT_EQ(testing::ReadTextFile(dir / "keep.exr"), before);
  // No temporary file is left behind.
  int files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path()))
    ++files;
  EXPECT_EQ(files, 1);
}

TEST(ImageIo, WriteWhereNoFileCanBeCreatedIsAnError) {
  // /proc refuses new files even for root, so this runs everywhere.
  try {
    WriteImage("/proc/hdr4d_cannot_write/a.exr", Image(2, 2, 3));
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/proc/hdr4d_cannot_write/a.exr"), std::string::npos)
        << e.what();
  }
}

TEST(ImageIo, WriteToAFileInPlaceOfAFolderIsAnError) {
  TempDir dir;
  testing::WriteTextFile(dir / "blocker", "x");
  try {
    WriteImage(dir / "blocker" / "a.png", Image(2, 2, 3, Encoding::kSrgb));
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("a.png"), std::string::npos);
  }
}

TEST(ImageIo, UnsupportedExtensionAndFormatMismatchAreErrors) {
  TempDir dir;
  const Image image(2, 2, 3);
  EXPECT_THROW(WriteImage(dir / "a.bmpx", image), Error);
  EXPECT_THROW(WriteImage(dir / "a.png", image, {.format = PixelFormat::kFloat}), Error);
  EXPECT_THROW(WriteImage(dir / "a.exr", image, {.format = PixelFormat::kUint8}), Error);
}

TEST(Image, SrgbConversionsInvertEachOther) {
  for (float v = 0.0f; v <= 1.0f; v += 0.01f) EXPECT_NEAR(SrgbToLinear(LinearToSrgb(v)), v, 1e-6);
  EXPECT_NEAR(LinearToSrgb(0.18f), 0.4613f, 1e-3);  // middle grey
  Image linear(1, 1, 4, Encoding::kLinear, 0.18f);
  const Image encoded = ToSrgb(linear);
  EXPECT_EQ(encoded.encoding(), Encoding::kSrgb);
  EXPECT_NEAR(encoded.values()[0], 0.4613f, 1e-3);
  EXPECT_FLOAT_EQ(encoded.values()[3], 0.18f);  // alpha untouched
  const Image grey_alpha = ToSrgb(Image(1, 1, 2, Encoding::kLinear, 0.18f));
  EXPECT_NEAR(grey_alpha.values()[0], 0.4613f, 1e-3);
  EXPECT_FLOAT_EQ(grey_alpha.values()[1], 0.18f);  // alpha untouched
}

// Alpha is the last channel of grey + alpha and of RGBA; Rgb() keeps the colour channels, and
// ExpandToRgb repeats grey into three.
TEST(Image, ColourChannelsLeaveAlphaOut) {
  Image grey_alpha(2, 1, 2, Encoding::kSrgb);
  grey_alpha.values() = {0.25f, 1.0f, 0.5f, 0.0f};
  EXPECT_EQ(grey_alpha.ColourChannelCount(), 1);
  EXPECT_EQ(grey_alpha.Rgb().values(), (std::vector<float>{0.25f, 0.5f}));
  EXPECT_EQ(ExpandToRgb(grey_alpha).values(),
            (std::vector<float>{0.25f, 0.25f, 0.25f, 0.5f, 0.5f, 0.5f}));
  Image rgba(1, 1, 4, Encoding::kSrgb);
  rgba.values() = {0.1f, 0.2f, 0.3f, 0.0f};
  EXPECT_EQ(rgba.ColourChannelCount(), 3);
  EXPECT_EQ(ExpandToRgb(rgba).values(), (std::vector<float>{0.1f, 0.2f, 0.3f}));
  EXPECT_EQ(Image(1, 1, 1, Encoding::kSrgb, 0.5f).ColourChannelCount(), 1);
  EXPECT_EQ(ExpandToRgb(Image(1, 1, 1, Encoding::kSrgb, 0.5f)).channels(), 3);
}

}  // namespace
}  // namespace hdr4d

namespace hdr4d {
namespace {
// Issue 51, case 14: OpenImageIO multiplied an RGBA PNG's colour by its alpha on reading (and
// divided by it on writing), so a render with the right RGB at alpha 128 scored 11 dB.
TEST(ImageIo, RgbaPngColourIsReadAsStoredNotPremultiplied) {
  TempDir dir;
  Image rgba(2, 2, 4, Encoding::kSrgb, 0.0f);
  for (int p = 0; p < 4; ++p) {
    rgba.data()[p * 4 + 0] = 0.8f;
    rgba.data()[p * 4 + 1] = 0.6f;
    rgba.data()[p * 4 + 2] = 0.4f;
    rgba.data()[p * 4 + 3] = 128.0f / 255.0f;
  }
  WriteImage(dir / "a.png", rgba);
  const Image back = ReadImage(dir / "a.png");
  ASSERT_EQ(back.channels(), 4);
  for (int c = 0; c < 4; ++c) EXPECT_NEAR(back.data()[c], rgba.data()[c], 0.5f / 255.0f) << c;
}
}  // namespace
}  // namespace hdr4d
