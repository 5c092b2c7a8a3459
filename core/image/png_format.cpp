// PNG files through libpng's classic interface (the simplified one converts 16-bit values as
// linear light and premultiplies alpha; the values must come back as stored). libpng reports
// errors by longjmp, so every libpng call runs in a function whose frame holds no C++ object
// with a destructor, and the error is thrown after it has returned.
#include <png.h>

#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <new>
#include <system_error>
#include <vector>

#include "core/image/image_formats.h"
#include "core/util/error.h"

namespace hdr4d::image_formats {
namespace fs = std::filesystem;

namespace {

struct PngSession {
  png_structp png = nullptr;
  png_infop info = nullptr;
  std::FILE* file = nullptr;
  bool writing = false;
  char error[256] = "";
  ~PngSession() {
    if (png != nullptr && writing) png_destroy_write_struct(&png, info ? &info : nullptr);
    if (png != nullptr && !writing) png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
    if (file != nullptr) std::fclose(file);
  }
};

void PngOnError(png_structp png, png_const_charp message) {
  auto* session = static_cast<PngSession*>(png_get_error_ptr(png));
  std::snprintf(session->error, sizeof(session->error), "%s", message);
  png_longjmp(png, 1);
}

// Warnings (an unknown colour profile, a text chunk out of place) do not make a file unreadable.
void PngOnWarning(png_structp, png_const_charp) {}

bool LittleEndianHost() {
  const std::uint16_t probe = 1;
  unsigned char first = 0;
  std::memcpy(&first, &probe, 1);
  return first == 1;
}

// Reads the header and sets the expansions (palette to RGB, low-bit grey to 8 bit, tRNS to an
// alpha channel, 16-bit samples in the host's order). False with session.error set on failure.
bool PngStartRead(PngSession& s, Header* header, int* bits) {
  if (setjmp(png_jmpbuf(s.png))) return false;
  png_init_io(s.png, s.file);
  png_read_info(s.png, s.info);
  const int color = png_get_color_type(s.png, s.info);
  const int depth = png_get_bit_depth(s.png, s.info);
  if (color == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(s.png);
  if (color == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(s.png);
  if (png_get_valid(s.png, s.info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(s.png);
  if (depth == 16 && LittleEndianHost()) png_set_swap(s.png);
  png_set_interlace_handling(s.png);
  png_read_update_info(s.png, s.info);
  header->width = static_cast<int>(png_get_image_width(s.png, s.info));
  header->height = static_cast<int>(png_get_image_height(s.png, s.info));
  header->channels = png_get_channels(s.png, s.info);
  header->is_float = false;
  *bits = png_get_bit_depth(s.png, s.info);
  return true;
}

bool PngFinishRead(PngSession& s, png_bytepp rows) {
  if (setjmp(png_jmpbuf(s.png))) return false;
  png_read_image(s.png, rows);
  png_read_end(s.png, nullptr);
  return true;
}

// Opens the file and reads its header (with the expansions set): what both readers start with.
Header StartPng(const fs::path& path, PngSession& s, int* bits) {
  s.file = std::fopen(path.c_str(), "rb");
  if (s.file == nullptr) Fail("{}: cannot open: {}", path.string(), std::strerror(errno));
  s.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &s, PngOnError, PngOnWarning);
  if (s.png != nullptr) s.info = png_create_info_struct(s.png);
  if (s.png == nullptr || s.info == nullptr) Fail("{}: cannot read image: out of memory", path.string());
  Header header;
  if (!PngStartRead(s, &header, bits)) Fail("{}: cannot read image: {}", path.string(), s.error);
  return header;
}

}  // namespace

Header ReadPngHeader(const fs::path& path) {
  PngSession s;
  int bits = 0;
  return StartPng(path, s, &bits);
}

Image ReadPng(const fs::path& path) {
  PngSession s;
  int bits = 0;
  const Header h = StartPng(path, s, &bits);
  if (h.width <= 0 || h.height <= 0 || h.channels <= 0)
    Fail("{}: image has no pixels ({}x{}x{})", path.string(), h.width, h.height, h.channels);
  const std::size_t row_bytes = static_cast<std::size_t>(h.width) * h.channels * (bits / 8);
  const std::size_t bytes = row_bytes * h.height;
  // Deflate packs at most about 1032:1, and expanding 1-bit palette indices to 8-bit RGBA is 32x
  // more: a header claiming far more pixels than that is a damaged file, refused before its
  // buffer is asked for (a 100-byte file claiming 30000x30000 RGBA16 ended in bad_alloc).
  constexpr std::uintmax_t kMaxExpansion = 1032 * 32, kAlwaysAllowed = std::uintmax_t(64) << 20;
  std::error_code ec;
  const std::uintmax_t file_bytes = bytes > kAlwaysAllowed ? fs::file_size(path, ec) : 0;
  if (bytes > kAlwaysAllowed && !ec && bytes / kMaxExpansion > file_bytes)
    Fail("{}: cannot read image: its header claims {}x{} ({} channels, {} MB decoded), which {} "
         "bytes cannot hold: the file is damaged", path.string(), h.width, h.height, h.channels,
         bytes >> 20, file_bytes);
  std::vector<unsigned char> data;
  try {
    data.resize(bytes);
  } catch (const std::bad_alloc&) {
    Fail("{}: cannot read image: not enough memory for {}x{} ({} MB)", path.string(), h.width,
         h.height, bytes >> 20);
  }
  std::vector<png_bytep> rows(h.height);
  for (int y = 0; y < h.height; ++y) rows[y] = data.data() + y * row_bytes;
  if (!PngFinishRead(s, rows.data())) Fail("{}: cannot decode image: {}", path.string(), s.error);
  Image image(h.width, h.height, h.channels, Encoding::kSrgb);
  float* out = image.data();
  const std::size_t n = static_cast<std::size_t>(h.width) * h.height * h.channels;
  if (bits == 16) {
    const auto* values = reinterpret_cast<const std::uint16_t*>(data.data());
    for (std::size_t i = 0; i < n; ++i) out[i] = values[i] / 65535.0f;
  } else {
    for (std::size_t i = 0; i < n; ++i) out[i] = data[i] / 255.0f;
  }
  return image;
}

namespace {

bool PngWriteAll(PngSession& s, const Image& image, int bits, int level, png_bytepp rows) {
  if (setjmp(png_jmpbuf(s.png))) return false;
  static const int kColor[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                               PNG_COLOR_TYPE_RGB_ALPHA};
  png_init_io(s.png, s.file);
  png_set_IHDR(s.png, s.info, image.width(), image.height(), bits, kColor[image.channels() - 1],
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (level >= 0) png_set_compression_level(s.png, level);
  // Tells viewers how the values are meant: display-encoded sRGB, or linear values on purpose.
  if (image.encoding() == Encoding::kSrgb) {
    png_set_sRGB(s.png, s.info, PNG_sRGB_INTENT_PERCEPTUAL);
  } else {
    png_set_gAMA(s.png, s.info, 1.0);
  }
  png_write_info(s.png, s.info);
  if (bits == 16 && LittleEndianHost()) png_set_swap(s.png);
  png_write_image(s.png, rows);
  png_write_end(s.png, nullptr);
  return true;
}

}  // namespace

void WritePng(const fs::path& path, const fs::path& tmp, const Image& image, int bits, int level) {
  const int channels = image.channels();
  if (channels < 1 || channels > 4)
    Fail("{}: PNG holds 1-4 channels, image has {}", path.string(), channels);
  const std::size_t n = static_cast<std::size_t>(image.width()) * channels;
  std::vector<unsigned char> data(n * image.height() * (bits / 8));
  const float* in = image.data();
  if (bits == 16) {
    auto* values = reinterpret_cast<std::uint16_t*>(data.data());
    for (std::size_t i = 0; i < n * image.height(); ++i) values[i] = ToCode(in[i], 65535);
  } else {
    for (std::size_t i = 0; i < n * image.height(); ++i) data[i] = ToCode(in[i], 255);
  }
  std::vector<png_bytep> rows(image.height());
  for (int y = 0; y < image.height(); ++y) rows[y] = data.data() + y * n * (bits / 8);

  PngSession s;
  s.writing = true;
  s.file = std::fopen(tmp.c_str(), "wb");
  if (s.file == nullptr)
    Fail("{}: cannot open for writing: {}", path.string(), std::strerror(errno));
  s.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &s, PngOnError, PngOnWarning);
  if (s.png != nullptr) s.info = png_create_info_struct(s.png);
  if (s.png == nullptr || s.info == nullptr) Fail("{}: write failed: out of memory", path.string());
  if (!PngWriteAll(s, image, bits, level, rows.data()))
    Fail("{}: write failed: {}", path.string(), s.error);
  std::FILE* file = s.file;
  s.file = nullptr;
  if (std::fflush(file) != 0 || std::ferror(file) != 0) {
    const int err = errno;
    std::fclose(file);
    Fail("{}: write failed: {}", path.string(), std::strerror(err));
  }
  if (std::fclose(file) != 0) Fail("{}: write failed: {}", path.string(), std::strerror(errno));
}

}  // namespace hdr4d::image_formats
