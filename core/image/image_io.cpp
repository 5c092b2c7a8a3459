#include "core/image/image_io.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <new>
#include <string>
#include <system_error>

#include "core/files/atomic_file.h"
#include "core/util/error.h"
#include "core/files/file_access.h"
#include "core/image/image_formats.h"
#include "core/image/png_structure.h"

namespace hdr4d {
namespace fs = std::filesystem;
namespace formats = image_formats;

namespace {

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// Checks what every reader needs (a readable file, not a folder; a PNG structurally sound, since
// libpng would print its own line for a broken one) and names the format by the first bytes.
// `whole_file`: the pixels will be decoded, so a PNG is checked up to its last chunk.
formats::FileFormat OpenInput(const fs::path& path, bool whole_file) {
  if (std::string problem = InputFileProblem(path); !problem.empty()) {
    if (ProbePath(path).kind == PathKind::kFolder) problem = "is a folder, expected an image";
    Fail("{}: {}", path.string(), problem);
  }
  const formats::FileFormat format = formats::SniffFormat(path);
  if (format == formats::FileFormat::kPng) {
    if (std::string problem = PngStructureProblem(path, whole_file); !problem.empty())
      Fail("{}: cannot read image: {}", path.string(), problem);
  }
  if (format == formats::FileFormat::kUnknown)
    Fail("{}: cannot read image: not an EXR, PNG, JPEG, TIFF or Radiance HDR file",
         path.string());
  return format;
}

}  // namespace

namespace image_formats {

FileFormat SniffFormat(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char m[10] = {};
  in.read(reinterpret_cast<char*>(m), sizeof(m));
  const std::streamsize n = in.gcount();
  const auto starts = [&](const char* magic, std::size_t size) {
    return n >= static_cast<std::streamsize>(size) && std::memcmp(m, magic, size) == 0;
  };
  if (starts("\x76\x2f\x31\x01", 4)) return FileFormat::kExr;
  if (starts("\x89PNG", 4)) return FileFormat::kPng;
  if (starts("\xff\xd8\xff", 3)) return FileFormat::kJpeg;
  if (starts("II*\0", 4) || starts("MM\0*", 4)) return FileFormat::kTiff;
  if (starts("#?RADIANCE", 10) || starts("#?RGBE", 6)) return FileFormat::kRgbe;
  return FileFormat::kUnknown;
}

}  // namespace image_formats

bool IsHdrPath(const fs::path& path) {
  const std::string ext = Lower(path.extension().string());
  return ext == ".exr" || ext == ".hdr";
}

bool IsImagePath(const fs::path& path) {
  static const char* const kExtensions[] = {".png", ".jpg", ".jpeg", ".exr",
                                            ".hdr", ".tif", ".tiff"};
  const std::string ext = Lower(path.extension().string());
  return std::any_of(std::begin(kExtensions), std::end(kExtensions),
                     [&](const char* known) { return ext == known; });
}

ImageSpecInfo ReadImageSpec(const fs::path& path) {
  formats::Header h;
  switch (OpenInput(path, /*whole_file=*/false)) {
    case formats::FileFormat::kExr: h = formats::ReadExrHeader(path); break;
    case formats::FileFormat::kPng: h = formats::ReadPngHeader(path); break;
    case formats::FileFormat::kJpeg: h = formats::ReadJpegHeader(path); break;
    case formats::FileFormat::kTiff: h = formats::ReadTiffHeader(path); break;
    case formats::FileFormat::kRgbe: h = formats::ReadRgbeHeader(path); break;
    case formats::FileFormat::kUnknown: break;  // OpenInput refused it
  }
  return {h.width, h.height, h.channels, h.is_float};
}

Image ReadImage(const fs::path& path, const ImageReadOptions& options) {
  Image image;
  try {
    switch (OpenInput(path, /*whole_file=*/true)) {
      case formats::FileFormat::kExr: image = formats::ReadExr(path); break;
      case formats::FileFormat::kPng: image = formats::ReadPng(path); break;
      case formats::FileFormat::kJpeg: image = formats::ReadJpeg(path); break;
      case formats::FileFormat::kTiff: image = formats::ReadTiff(path); break;
      case formats::FileFormat::kRgbe: image = formats::ReadRgbe(path); break;
      case formats::FileFormat::kUnknown: break;
    }
  } catch (const std::bad_alloc&) {  // a header's size beyond this machine's memory
    const ImageSpecInfo spec = ReadImageSpec(path);
    Fail("{}: cannot read image: not enough memory for {}x{}x{} values (is the file damaged?)",
         path.string(), spec.width, spec.height, spec.channels);
  }
  if (image.empty()) Fail("{}: image has no pixels", path.string());
  if (options.require_finite) {
    const long bad = FirstNonFinite(image);
    if (bad >= 0) {
      const long pixel = bad / image.channels();
      Fail("{}: non-finite pixel value ({}) at x={}, y={}, channel {}", path.string(),
           image.values()[bad], pixel % image.width(), pixel / image.width(),
           bad % image.channels());
    }
  }
  return image;
}

void WriteImage(const fs::path& path, const Image& image, const ImageWriteOptions& options) {
  if (image.empty()) Fail("{}: refusing to write an empty image", path.string());
  const std::string ext = Lower(path.extension().string());
  const bool exr = ext == ".exr", png = ext == ".png", jpeg = ext == ".jpg" || ext == ".jpeg";
  if (!exr && !png && !jpeg) {
    Fail("{}: unsupported output format '{}' (use .exr, .png, .jpg)", path.string(), ext);
  }
  PixelFormat format = options.format;
  if (format == PixelFormat::kAuto) format = exr ? PixelFormat::kHalf : PixelFormat::kUint8;
  const bool is_float = format == PixelFormat::kHalf || format == PixelFormat::kFloat;
  if (exr && !is_float) Fail("{}: EXR is written as half or float", path.string());
  if (!exr && is_float)
    Fail("{}: {} stores integers; use .exr for float pixels", path.string(), ext);
  if (jpeg && format != PixelFormat::kUint8) Fail("{}: JPEG is 8 bit only", path.string());
  if (jpeg && image.channels() != 1 && image.channels() != 3) {
    Fail("{}: JPEG needs 1 or 3 channels, image has {}", path.string(), image.channels());
  }

  // Integer formats: clamp to [0,1] explicitly so NaN and out-of-range values have one defined
  // result. Alpha is written as stored: RGB is never divided by it on the way out.
  Image clamped;
  if (!exr) {
    clamped = image;
    for (float& v : clamped.values()) v = std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, 1.0f);
  }
  // The temporary file has no image extension, so the format comes from the target's. No
  // writer stamps a date: equal images written at different times are equal byte for byte.
  const auto fill = [&](const fs::path& tmp) {
    if (exr) {
      formats::WriteExr(path, tmp, image, format == PixelFormat::kHalf);
    } else if (png) {
      formats::WritePng(path, tmp, clamped, format == PixelFormat::kUint16 ? 16 : 8,
                        std::min(options.png_compression, 9));
    } else {
      formats::WriteJpeg(path, tmp, clamped, options.jpeg_quality);
    }
  };
  if (options.batch != nullptr) {
    options.batch->Write(path, fill);
  } else {
    WriteFileAtomicAt(path, fill);
  }
}

}  // namespace hdr4d
