// TIFF files through libtiff: 8- and 16-bit unsigned and 32-bit float samples, grey or RGB(A),
// in strips, interleaved or in separate planes (what cameras' raw converters and image editors
// write). Tiled, palette and other photometric kinds are refused with the reason.
#include <tiffio.h>

#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/image/image_formats.h"
#include "core/util/error.h"

namespace hdr4d::image_formats {
namespace fs = std::filesystem;

namespace {

// libtiff prints errors and warnings on stderr unless told otherwise; its handlers are global,
// so each thread keeps its last error for the Fail that follows.
thread_local std::string tiff_last_error;

void TiffOnError(const char*, const char* format, va_list args) {
  char text[512];
  std::vsnprintf(text, sizeof(text), format, args);
  tiff_last_error = text;
}

void TiffOnWarning(const char*, const char*, va_list) {}

struct TiffCloser {
  void operator()(TIFF* tif) const { TIFFClose(tif); }
};
using TiffHandle = std::unique_ptr<TIFF, TiffCloser>;

TiffHandle OpenTiff(const fs::path& path) {
  static std::once_flag once;
  std::call_once(once, [] {
    TIFFSetErrorHandler(TiffOnError);
    TIFFSetWarningHandler(TiffOnWarning);
  });
  tiff_last_error.clear();
  TiffHandle tif(TIFFOpen(path.c_str(), "r"));
  if (!tif) Fail("{}: cannot read image: {}", path.string(),
                 tiff_last_error.empty() ? "not a readable TIFF file" : tiff_last_error);
  return tif;
}

struct TiffLayout {
  Header header;
  int bits = 0;
  int planar = PLANARCONFIG_CONTIG;
};

TiffLayout ReadLayout(const fs::path& path, TIFF* tif) {
  std::uint32_t width = 0, height = 0;
  std::uint16_t samples = 1, bits = 8, format = SAMPLEFORMAT_UINT, photometric = 0, planar = 1;
  TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, &width);
  TIFFGetField(tif, TIFFTAG_IMAGELENGTH, &height);
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLESPERPIXEL, &samples);
  TIFFGetFieldDefaulted(tif, TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLEFORMAT, &format);
  TIFFGetFieldDefaulted(tif, TIFFTAG_PLANARCONFIG, &planar);
  TIFFGetField(tif, TIFFTAG_PHOTOMETRIC, &photometric);
  const bool is_float = format == SAMPLEFORMAT_IEEEFP;
  if (TIFFIsTiled(tif)) Fail("{}: cannot read image: tiled TIFF (write it in strips)", path.string());
  if (photometric != PHOTOMETRIC_MINISBLACK && photometric != PHOTOMETRIC_RGB)
    Fail("{}: cannot read image: TIFF photometric {} (grey or RGB only)", path.string(), photometric);
  if (!((format == SAMPLEFORMAT_UINT && (bits == 8 || bits == 16)) || (is_float && bits == 32)))
    Fail("{}: cannot read image: TIFF with {}-bit {} samples (8/16-bit unsigned or 32-bit float)",
         path.string(), bits, is_float ? "float" : "integer");
  if (samples < 1 || samples > 4)
    Fail("{}: cannot read image: TIFF with {} samples per pixel", path.string(), samples);
  return {{static_cast<int>(width), static_cast<int>(height), samples, is_float}, bits, planar};
}

float SampleValue(const unsigned char* line, int index, int bits) {
  if (bits == 8) return line[index] / 255.0f;
  if (bits == 16) {
    std::uint16_t v;
    std::memcpy(&v, line + 2 * index, 2);
    return v / 65535.0f;
  }
  float v;
  std::memcpy(&v, line + 4 * index, 4);
  return v;
}

}  // namespace

Header ReadTiffHeader(const fs::path& path) {
  TiffHandle tif = OpenTiff(path);
  return ReadLayout(path, tif.get()).header;
}

Image ReadTiff(const fs::path& path) {
  TiffHandle tif = OpenTiff(path);
  const TiffLayout layout = ReadLayout(path, tif.get());
  const Header& h = layout.header;
  if (h.width <= 0 || h.height <= 0)
    Fail("{}: image has no pixels ({}x{})", path.string(), h.width, h.height);
  Image image(h.width, h.height, h.channels, h.is_float ? Encoding::kLinear : Encoding::kSrgb);
  std::vector<unsigned char> line(TIFFScanlineSize(tif.get()));
  const bool separate = layout.planar == PLANARCONFIG_SEPARATE;
  for (int plane = 0; plane < (separate ? h.channels : 1); ++plane) {
    for (int y = 0; y < h.height; ++y) {
      if (TIFFReadScanline(tif.get(), line.data(), y, static_cast<std::uint16_t>(plane)) < 0)
        Fail("{}: cannot decode image: {}", path.string(),
             tiff_last_error.empty() ? "truncated or corrupt pixel data" : tiff_last_error);
      float* row = image.data() + static_cast<std::size_t>(y) * h.width * h.channels;
      for (int x = 0; x < h.width; ++x) {
        if (separate) {
          row[x * h.channels + plane] = SampleValue(line.data(), x, layout.bits);
        } else {
          for (int c = 0; c < h.channels; ++c)
            row[x * h.channels + c] = SampleValue(line.data(), x * h.channels + c, layout.bits);
        }
      }
    }
  }
  return image;
}

}  // namespace hdr4d::image_formats
