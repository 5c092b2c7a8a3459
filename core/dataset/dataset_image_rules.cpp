#include "core/dataset/dataset_image_rules.h"

#include <fmt/format.h>

#include "core/util/error.h"

namespace hdr4d {

std::string LdrImageHeaderProblem(const ImageSpecInfo& spec) {
  if (spec.linear) {
    return "is a linear HDR image (float pixels); file_path is the frame's LDR image (PNG/JPEG), "
           "HDR ground truth belongs in exr_file_path";
  }
  if (spec.channels < 1 || spec.channels > 4)
    return fmt::format("has {} channels; an LDR image must be grey, grey + alpha, RGB or RGBA",
                       spec.channels);
  return "";
}

std::string HdrImageHeaderProblem(const ImageSpecInfo& spec) {
  if (!spec.linear) {
    return "is a display-encoded image (integer pixels); exr_file_path must be linear HDR "
           "radiance (EXR/HDR)";
  }
  if (spec.channels < 3)
    return fmt::format("has {} channel{}; HDR ground truth needs RGB", spec.channels,
                       spec.channels == 1 ? "" : "s");
  return "";
}

namespace {

ImageSpecInfo SpecOf(const Image& image) {
  return {image.width(), image.height(), image.channels(),
          image.encoding() == Encoding::kLinear};
}

}  // namespace

std::string LdrImageProblem(const Image& image) { return LdrImageHeaderProblem(SpecOf(image)); }

std::string HdrImageProblem(const Image& image) {
  if (std::string p = HdrImageHeaderProblem(SpecOf(image)); !p.empty()) return p;
  const int c = image.channels();
  float max_value = 0;
  for (std::size_t p = 0; p < image.num_pixels(); ++p) {
    for (int k = 0; k < 3; ++k) {
      const float v = image.data()[p * c + k];
      if (v < 0) {
        return fmt::format(
            "negative radiance {} at x={}, y={}, channel {}; HDR values must be >= 0", v,
            p % image.width(), p / image.width(), k);
      }
      max_value = std::max(max_value, v);
    }
  }
  if (!(max_value > 0)) return "has no positive value (all black); HDR ground truth needs light";
  return "";
}

Image ReadHdrGroundTruth(const std::filesystem::path& path) {
  Image image = ReadImage(path);  // refuses NaN / Inf with the pixel
  if (std::string p = HdrImageProblem(image); !p.empty()) Fail("{}: {}", path.string(), p);
  return image;
}

}  // namespace hdr4d
