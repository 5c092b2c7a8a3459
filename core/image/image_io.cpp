#include "core/image/image_io.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <string>
#include <system_error>

#include "core/files/atomic_file.h"
#include "core/util/error.h"
#include "core/files/file_access.h"
#include "core/image/png_structure.h"

namespace hdr4d {
namespace fs = std::filesystem;
namespace OIIO = OIIO_NAMESPACE;

namespace {

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// OpenImageIO may pile several lines into one error; the first says what went wrong.
std::string FirstLine(std::string text) {
  const std::size_t end = text.find('\n');
  if (end != std::string::npos) text.resize(end);
  return text;
}

bool HasPngSignature(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[4] = {};
  return in.read(magic, 4) && std::memcmp(magic, "\x89PNG", 4) == 0;
}

// `whole_file`: the pixels will be decoded, so a PNG is checked up to its last chunk.
std::unique_ptr<OIIO::ImageInput> OpenInput(const fs::path& path, bool whole_file) {
  if (std::string problem = InputFileProblem(path); !problem.empty()) {
    if (ProbePath(path).kind == PathKind::kFolder) problem = "is a folder, expected an image";
    Fail("{}: {}", path.string(), problem);
  }
  // libpng prints a line of its own on stderr for a broken file: such files never reach it.
  if (HasPngSignature(path)) {
    if (std::string problem = PngStructureProblem(path, whole_file); !problem.empty())
      Fail("{}: cannot read image: {}", path.string(), problem);
  }
  // Colour channels as stored: OpenImageIO's default multiplies RGB by alpha on reading a PNG
  // (issue 51, case 14), so eval scored a render with the right RGB at alpha 128 as 11 dB and
  // training, compositing over the background afterwards, learned rgb x alpha^2.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path.string(), &config);
  if (!in) {
    std::string why = FirstLine(OIIO::geterror());
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
  auto in = OpenInput(path, /*whole_file=*/false);
  const OIIO::ImageSpec& spec = in->spec();
  return {spec.width, spec.height, spec.nchannels, spec.format.is_floating_point()};
}

Image ReadImage(const fs::path& path, const ImageReadOptions& options) {
  auto in = OpenInput(path, /*whole_file=*/true);
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
    std::string why = FirstLine(in->geterror());
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

  // Integer formats: clamp to [0,1] explicitly so NaN and out-of-range values have one defined
  // result.
  const float* pixels = image.data();
  std::vector<float> clamped;
  if (!exr) {
    clamped = image.values();
    for (float& v : clamped) v = std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, 1.0f);
    pixels = clamped.data();
  }

  OIIO::ImageSpec spec(image.width(), image.height(), image.channels(), type);
  if (jpeg) spec.attribute("Compression", "jpeg:" + std::to_string(options.jpeg_quality));
  if (exr) spec.attribute("compression", "zip");
  if (png && options.png_compression >= 0)
    spec.attribute("png:compressionLevel", std::min(options.png_compression, 9));
  // No capture date in the header: OpenImageIO would stamp the current time, and equal images
  // written at different times would differ byte for byte (reproducible datasets need them equal).
  spec.attribute("DateTime", "");
  // RGB is written as stored, as ReadImage reads it: not divided by alpha on the way out.
  if (image.channels() == 4) spec.attribute("oiio:UnassociatedAlpha", 1);
  if (!exr)
    spec.attribute("oiio:ColorSpace", image.encoding() == Encoding::kSrgb ? "sRGB" : "Linear");
  // The temporary file has no image extension, so the writer is chosen by the target's.
  const auto fill = [&](const fs::path& tmp) {
    auto out = OIIO::ImageOutput::create(path.string());
    if (!out) Fail("{}: no writer for this format: {}", path.string(), OIIO::geterror());
    if (!out->open(tmp.string(), spec)) {
      Fail("{}: cannot open for writing: {}", path.string(), FirstLine(out->geterror()));
    }
    const bool wrote = out->write_image(OIIO::TypeDesc::FLOAT, pixels);
    const std::string why = FirstLine(out->geterror());
    const bool closed = out->close();
    if (!wrote || !closed) {
      Fail("{}: write failed: {}", path.string(), why.empty() ? "unknown I/O error" : why);
    }
  };
  if (options.batch != nullptr) {
    options.batch->Write(path, fill);
  } else {
    WriteFileAtomicAt(path, fill);
  }
}

void DiscardImageLibraryErrors() { OIIO::geterror(/*clear=*/true); }

}  // namespace hdr4d
