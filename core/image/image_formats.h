// The image file formats behind image_io.h, one file each, on the format's own library: OpenEXR,
// libpng, libjpeg-turbo, libtiff; Radiance RGBE is read here. (OpenImageIO did this until
// 2026-12-02: Debian's build loads about 260 shared libraries, GDAL, DICOM and video codecs among
// them, which cost 0.6 s of CPU at the start of every hdr4d process and every test case.)
// Decoders return the values as stored: floats as they are (Encoding::kLinear), integers divided
// by their largest code (Encoding::kSrgb). Every failure throws hdr4d::Error naming `path`.
#pragma once

#include <filesystem>

#include "core/image/image.h"

namespace hdr4d::image_formats {

enum class FileFormat { kUnknown, kExr, kPng, kJpeg, kTiff, kRgbe };

// By the file's first bytes, not its name.
FileFormat SniffFormat(const std::filesystem::path& path);

struct Header {
  int width = 0;
  int height = 0;
  int channels = 0;
  bool is_float = false;
};

Header ReadExrHeader(const std::filesystem::path& path);
Image ReadExr(const std::filesystem::path& path);
Header ReadPngHeader(const std::filesystem::path& path);
Image ReadPng(const std::filesystem::path& path);
Header ReadJpegHeader(const std::filesystem::path& path);
Image ReadJpeg(const std::filesystem::path& path);
Header ReadTiffHeader(const std::filesystem::path& path);
Image ReadTiff(const std::filesystem::path& path);
Header ReadRgbeHeader(const std::filesystem::path& path);
Image ReadRgbe(const std::filesystem::path& path);

// Writers put the file at `tmp`; `path` is the name errors give. Integer writers expect values
// already clamped to [0,1].
void WriteExr(const std::filesystem::path& path, const std::filesystem::path& tmp,
              const Image& image, bool half);
// bits 8 or 16; level: zlib 0-9, or -1 for libpng's default.
void WritePng(const std::filesystem::path& path, const std::filesystem::path& tmp,
              const Image& image, int bits, int level);
void WriteJpeg(const std::filesystem::path& path, const std::filesystem::path& tmp,
               const Image& image, int quality);

// Integer code of a value in [0,1] (round to nearest), as the writers store it.
inline unsigned ToCode(float value, unsigned max_code) {
  return static_cast<unsigned>(value * static_cast<float>(max_code) + 0.5f);
}

}  // namespace hdr4d::image_formats
