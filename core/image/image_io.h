// Reading and writing images: OpenEXR (half or float), PNG (8 or 16 bit), JPEG; TIFF and Radiance
// HDR are read too (image_formats.h: one file per format, each on its own library). Errors name the file and the problem; writes go through WriteFileAtomic (temporary file,
// output guard, write-through for links and devices), so a failed write never leaves a
// truncated image behind.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "core/image/image.h"

namespace hdr4d {

enum class PixelFormat {
  kAuto,    // EXR: half; PNG/JPEG: 8 bit
  kUint8,   // PNG, JPEG
  kUint16,  // PNG
  kHalf,    // EXR
  kFloat,   // EXR
};

struct ImageReadOptions {
  // Reject NaN/Inf pixel values (EXR can hold them; a NeRF target must not).
  bool require_finite = true;
};

class FileBatch;

struct ImageWriteOptions {
  PixelFormat format = PixelFormat::kAuto;
  int jpeg_quality = 95;
  // PNG only: zlib level 0 (none) .. 9 (smallest); -1 keeps libpng's default (6). Level 1
  // writes an 800x800 render about 3x faster for files 30-45% larger
  // (docs/history/render-speed.md).
  int png_compression = -1;
  // Set: the image is one of a set moved into place together by batch->Commit()
  // (core/files/atomic_file.h); null: it is moved into place at once.
  FileBatch* batch = nullptr;
};

// True for file names whose format stores linear HDR values (.exr, .hdr).
bool IsHdrPath(const std::filesystem::path& path);

// True for the file names ReadImage reads (.png, .jpg/.jpeg, .exr, .hdr, .tif/.tiff).
bool IsImagePath(const std::filesystem::path& path);

// Reads EXR, PNG, JPEG, TIFF (8/16-bit, float) and Radiance HDR, told apart by their first bytes. EXR/HDR come back Encoding::kLinear, integer formats
// (PNG, JPEG, ...) come back Encoding::kSrgb with values scaled to [0,1] as stored. Alpha is
// unassociated: RGB as stored, never multiplied by alpha on reading (eval ignores alpha; training
// composites over the dataset background once, method/train/train_views.cpp).
// Throws hdr4d::Error naming the file for a missing, unreadable, corrupt or non-finite image.
Image ReadImage(const std::filesystem::path& path, const ImageReadOptions& options = {});

// Only the header: size, channels, float or integer. Throws like ReadImage.
struct ImageSpecInfo {
  int width = 0;
  int height = 0;
  int channels = 0;
  bool linear = false;  // float pixels (EXR/HDR: linear radiance), else integers (display-encoded)
};
ImageSpecInfo ReadImageSpec(const std::filesystem::path& path);

// Writes by extension. Integer formats are written as stored values: the caller chooses the
// encoding (ToSrgb before writing a linear image to PNG, or write the linear values on
// purpose); values are clamped to [0,1] and rounded. EXR keeps values exactly (float) or
// to half precision. Creates missing parent folders. Throws hdr4d::Error naming the file.
void WriteImage(const std::filesystem::path& path,
                const Image& image,
                const ImageWriteOptions& options = {});

// The exposure time in seconds the file records, if any: EXIF ExposureTime of a JPEG or TIFF,
// expTime of an EXR header. Throws like ReadImage for an unreadable file.
std::optional<double> ReadExposureTime(const std::filesystem::path& path);

}  // namespace hdr4d
