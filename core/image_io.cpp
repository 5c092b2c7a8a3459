#include "core/image_io.h"

#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <system_error>

#include "core/error.h"

namespace hdr4d {
namespace fs = std::filesystem;
namespace OIIO = OIIO_NAMESPACE;

namespace {

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::unique_ptr<OIIO::ImageInput> OpenInput(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) Fail("{}: file not found", path.string());
  if (fs::is_directory(path, ec)) Fail("{}: is a folder, expected an image", path.string());
  auto in = OIIO::ImageInput::open(path.string());
  if (!in) {
    std::string why = OIIO::geterror();
    if (why.empty()) why = "not a readable image";
    Fail("{}: cannot read image: {}", path.string(), why);
  }
  return in;
}

}  // namespace

bool IsHdrPath(const fs::path& path) {
  const std::string ext = Lower(path.extension().string());
  return ext == ".exr" || ext == ".hdr";
}

ImageSpecInfo ReadImageSpec(const fs::path& path) {
  auto in = OpenInput(path);
  const OIIO::ImageSpec& spec = in->spec();
  return {spec.width, spec.height, spec.nchannels};
}

Image ReadImage(const fs::path& path, const ImageReadOptions& options) {
  auto in = OpenInput(path);
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) {
    Fail("{}: image has no pixels ({}x{}x{})", path.string(), spec.width, spec.height,
         spec.nchannels);
  }
  // Integer formats are display-encoded values; float formats hold linear radiance.
  const bool is_float = spec.format.is_floating_point();
  Image image(spec.width, spec.height, spec.nchannels,
              is_float ? Encoding::kLinear : Encoding::kSrgb);
  // OIIO converts integer pixels to float in [0,1] (value / max code).
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.data())) {
    std::string why = in->geterror();
    if (why.empty()) why = "truncated or corrupt pixel data";
    Fail("{}: cannot decode image: {}", path.string(), why);
  }
  in->close();
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
  OIIO::TypeDesc type = OIIO::TypeDesc::UINT8;
  switch (options.format) {
    case PixelFormat::kAuto:
      type = exr ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::UINT8;
      break;
    case PixelFormat::kUint8:
      type = OIIO::TypeDesc::UINT8;
      break;
    case PixelFormat::kUint16:
      type = OIIO::TypeDesc::UINT16;
      break;
    case PixelFormat::kHalf:
      type = OIIO::TypeDesc::HALF;
      break;
    case PixelFormat::kFloat:
      type = OIIO::TypeDesc::FLOAT;
      break;
  }
  if (exr && !type.is_floating_point()) Fail("{}: EXR is written as half or float", path.string());
  if (!exr && type.is_floating_point())
    Fail("{}: {} stores integers; use .exr for float pixels", path.string(), ext);
  if (jpeg && type != OIIO::TypeDesc::UINT8) Fail("{}: JPEG is 8 bit only", path.string());
  if (jpeg && image.channels() != 1 && image.channels() != 3) {
    Fail("{}: JPEG needs 1 or 3 channels, image has {}", path.string(), image.channels());
  }

  std::error_code ec;
  if (path.has_parent_path()) {
    fs::create_directories(path.parent_path(), ec);
    if (ec)
      Fail("{}: cannot create folder {}: {}", path.string(), path.parent_path().string(),
           ec.message());
  }

  // Integer formats: clamp to [0,1] explicitly so NaN and out-of-range values have one defined
  // result.
  const float* pixels = image.data();
  std::vector<float> clamped;
  if (!exr) {
    clamped = image.values();
    for (float& v : clamped) v = std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, 1.0f);
    pixels = clamped.data();
  }

  // Write beside the target and rename, so a failure never leaves a half-written file.
  const fs::path tmp =
      path.parent_path() / (path.filename().string() + ".tmp" + std::to_string(getpid()) + ext);
  OIIO::ImageSpec spec(image.width(), image.height(), image.channels(), type);
  if (jpeg) spec.attribute("Compression", "jpeg:" + std::to_string(options.jpeg_quality));
  if (exr) spec.attribute("compression", "zip");
  // No capture date in the header: OpenImageIO would stamp the current time, and equal images
  // written at different times would differ byte for byte (reproducible datasets need them equal).
  spec.attribute("DateTime", "");
  if (!exr)
    spec.attribute("oiio:ColorSpace", image.encoding() == Encoding::kSrgb ? "sRGB" : "Linear");
  auto out = OIIO::ImageOutput::create(tmp.string());
  if (!out) Fail("{}: no writer for this format: {}", path.string(), OIIO::geterror());
  if (!out->open(tmp.string(), spec)) {
    Fail("{}: cannot open for writing: {}", path.string(), out->geterror());
  }
  const bool wrote = out->write_image(OIIO::TypeDesc::FLOAT, pixels);
  const std::string why = out->geterror();
  const bool closed = out->close();
  if (!wrote || !closed) {
    fs::remove(tmp, ec);
    Fail("{}: write failed: {}", path.string(), why.empty() ? "unknown I/O error" : why);
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    Fail("{}: cannot move the written image into place: {}", path.string(), ec.message());
  }
}

}  // namespace hdr4d
