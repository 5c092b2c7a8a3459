// Reading and writing images through OpenImageIO: OpenEXR (half or float), PNG (8 or 16 bit),
// JPEG. Errors name the file and the problem; a write goes to a temporary file first and is
// renamed into place, so a failed write never leaves a truncated image behind.
#pragma once

#include <filesystem>
#include <string>

#include "core/image.h"

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

struct ImageWriteOptions {
  PixelFormat format = PixelFormat::kAuto;
  int jpeg_quality = 95;
};

// True for file names whose format stores linear HDR values (.exr, .hdr).
bool IsHdrPath(const std::filesystem::path& path);

// Reads any format OpenImageIO knows. EXR/HDR come back Encoding::kLinear, integer formats
// (PNG, JPEG, ...) come back Encoding::kSrgb with values scaled to [0,1] as stored.
// Throws hdr4d::Error naming the file for a missing, unreadable, corrupt or non-finite image.
Image ReadImage(const std::filesystem::path& path, const ImageReadOptions& options = {});

// Only the header: width, height, channels. Throws like ReadImage.
struct ImageSpecInfo {
  int width = 0;
  int height = 0;
  int channels = 0;
};
ImageSpecInfo ReadImageSpec(const std::filesystem::path& path);

// Writes by extension. Integer formats are written as stored values: the caller chooses the
// encoding (ToSrgb before writing a linear image to PNG, or write the linear values on
// purpose); values are clamped to [0,1] and rounded. EXR keeps values exactly (float) or
// to half precision. Creates missing parent folders. Throws hdr4d::Error naming the file.
void WriteImage(const std::filesystem::path& path,
                const Image& image,
                const ImageWriteOptions& options = {});

}  // namespace hdr4d
