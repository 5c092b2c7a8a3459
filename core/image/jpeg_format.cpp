// JPEG files through libjpeg-turbo. libjpeg's default error handler exits the process, so errors
// longjmp back into the function that called it (whose frame holds no C++ object with a
// destructor) and are thrown from there. Corrupt-data warnings ("premature end of data") count
// as errors on reading: a damaged photograph must be refused, not read with grey blocks.
// jpeglib.h uses size_t and FILE without including their headers.
#include <cstddef>
#include <cstdio>
// clang-format off
#include <jpeglib.h>
// clang-format on

#include <csetjmp>
#include <cstring>
#include <vector>

#include "core/image/image_formats.h"
#include "core/util/error.h"

namespace hdr4d::image_formats {
namespace fs = std::filesystem;

namespace {

struct JpegErrors {
  jpeg_error_mgr manager;  // first: libjpeg hands the handlers a pointer to it
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX] = "";
};

void JpegOnError(j_common_ptr info) {
  auto* errors = reinterpret_cast<JpegErrors*>(info->err);
  (*info->err->format_message)(info, errors->message);
  std::longjmp(errors->jump, 1);
}

// Level -1 is a warning about the data (corrupt or truncated); the others are trace messages.
void JpegOnMessage(j_common_ptr info, int level) {
  auto* errors = reinterpret_cast<JpegErrors*>(info->err);
  if (level < 0 && errors->message[0] == '\0') (*info->err->format_message)(info, errors->message);
  if (level < 0) info->err->num_warnings++;
}

struct JpegReadSession {
  jpeg_decompress_struct info{};
  JpegErrors errors;
  std::FILE* file = nullptr;
  bool created = false;
  ~JpegReadSession() {
    if (created) jpeg_destroy_decompress(&info);
    if (file != nullptr) std::fclose(file);
  }
};

// Opens the decoder and reads the header; with `pixels` also decodes into it (sized by the
// caller from a first call's header). False with the message set on failure.
bool JpegRead(JpegReadSession& s, Header* header, unsigned char* pixels) {
  s.info.err = jpeg_std_error(&s.errors.manager);
  s.errors.manager.error_exit = JpegOnError;
  s.errors.manager.emit_message = JpegOnMessage;
  if (setjmp(s.errors.jump)) return false;
  jpeg_create_decompress(&s.info);
  s.created = true;
  jpeg_stdio_src(&s.info, s.file);
  jpeg_read_header(&s.info, TRUE);
  if (s.info.jpeg_color_space == JCS_CMYK || s.info.jpeg_color_space == JCS_YCCK) {
    std::snprintf(s.errors.message, sizeof(s.errors.message), "CMYK JPEG is not supported");
    return false;
  }
  s.info.out_color_space = s.info.num_components == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_calc_output_dimensions(&s.info);
  *header = {static_cast<int>(s.info.output_width), static_cast<int>(s.info.output_height),
             s.info.output_components, false};
  if (pixels == nullptr) return true;
  jpeg_start_decompress(&s.info);
  const std::size_t row = static_cast<std::size_t>(header->width) * header->channels;
  while (s.info.output_scanline < s.info.output_height) {
    JSAMPROW line = pixels + s.info.output_scanline * row;
    jpeg_read_scanlines(&s.info, &line, 1);
  }
  jpeg_finish_decompress(&s.info);
  return s.errors.manager.num_warnings == 0;
}

void OpenJpeg(const fs::path& path, JpegReadSession& s) {
  s.file = std::fopen(path.c_str(), "rb");
  if (s.file == nullptr) Fail("{}: cannot open: {}", path.string(), std::strerror(errno));
}

}  // namespace

Header ReadJpegHeader(const fs::path& path) {
  JpegReadSession s;
  OpenJpeg(path, s);
  Header header;
  if (!JpegRead(s, &header, nullptr))
    Fail("{}: cannot read image: {}", path.string(), s.errors.message);
  return header;
}

Image ReadJpeg(const fs::path& path) {
  Header header = ReadJpegHeader(path);
  if (header.width <= 0 || header.height <= 0)
    Fail("{}: image has no pixels ({}x{})", path.string(), header.width, header.height);
  std::vector<unsigned char> pixels(static_cast<std::size_t>(header.width) * header.height *
                                    header.channels);
  JpegReadSession s;
  OpenJpeg(path, s);
  if (!JpegRead(s, &header, pixels.data()))
    Fail("{}: cannot decode image: {}", path.string(),
         s.errors.message[0] ? s.errors.message : "truncated or corrupt pixel data");
  Image image(header.width, header.height, header.channels, Encoding::kSrgb);
  for (std::size_t i = 0; i < pixels.size(); ++i) image.data()[i] = pixels[i] / 255.0f;
  return image;
}

namespace {

struct JpegWriteSession {
  jpeg_compress_struct info{};
  JpegErrors errors;
  std::FILE* file = nullptr;
  bool created = false;
  ~JpegWriteSession() {
    if (created) jpeg_destroy_compress(&info);
    if (file != nullptr) std::fclose(file);
  }
};

bool JpegWriteAll(JpegWriteSession& s, int width, int height, int channels, int quality,
                  unsigned char* pixels) {
  s.info.err = jpeg_std_error(&s.errors.manager);
  s.errors.manager.error_exit = JpegOnError;
  if (setjmp(s.errors.jump)) return false;
  jpeg_create_compress(&s.info);
  s.created = true;
  jpeg_stdio_dest(&s.info, s.file);
  s.info.image_width = width;
  s.info.image_height = height;
  s.info.input_components = channels;
  s.info.in_color_space = channels == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_set_defaults(&s.info);
  jpeg_set_quality(&s.info, quality, TRUE);
  jpeg_start_compress(&s.info, TRUE);
  const std::size_t row = static_cast<std::size_t>(width) * channels;
  while (s.info.next_scanline < s.info.image_height) {
    JSAMPROW line = pixels + s.info.next_scanline * row;
    jpeg_write_scanlines(&s.info, &line, 1);
  }
  jpeg_finish_compress(&s.info);
  return true;
}

}  // namespace

void WriteJpeg(const fs::path& path, const fs::path& tmp, const Image& image, int quality) {
  std::vector<unsigned char> pixels(image.values().size());
  for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = ToCode(image.data()[i], 255);
  JpegWriteSession s;
  s.file = std::fopen(tmp.c_str(), "wb");
  if (s.file == nullptr)
    Fail("{}: cannot open for writing: {}", path.string(), std::strerror(errno));
  if (!JpegWriteAll(s, image.width(), image.height(), image.channels(), quality, pixels.data()))
    Fail("{}: write failed: {}", path.string(), s.errors.message);
  std::FILE* file = s.file;
  s.file = nullptr;
  const bool flushed = std::fflush(file) == 0 && std::ferror(file) == 0;
  const int err = errno;
  if (std::fclose(file) != 0 || !flushed)
    Fail("{}: write failed: {}", path.string(), std::strerror(flushed ? errno : err));
}

}  // namespace hdr4d::image_formats
