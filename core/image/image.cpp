#include "core/image/image.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/util/error.h"

namespace hdr4d {

const char* EncodingName(Encoding encoding) {
  return encoding == Encoding::kLinear ? "linear" : "sRGB";
}

Image::Image(int width, int height, int channels, Encoding encoding, float fill)
    : width_(width), height_(height), channels_(channels), encoding_(encoding) {
  HDR4D_CHECK(width >= 0 && height >= 0 && channels >= 0);
  data_.assign(static_cast<std::size_t>(width) * height * channels, fill);
}

std::string Image::ShapeString() const {
  return std::to_string(width_) + "x" + std::to_string(height_) + "x" + std::to_string(channels_);
}

float Image::MaxValue() const {
  float m = -std::numeric_limits<float>::infinity();
  for (float v : data_) m = std::max(m, v);
  return m;
}

Image Image::Rgb() const {
  if (channels_ == 0) Fail("image has no channels");
  const int colour = ColourChannelCount();
  if (colour == channels_) return *this;
  Image rgb(width_, height_, colour, encoding_);
  for (std::size_t i = 0; i < num_pixels(); ++i) {
    for (int c = 0; c < colour; ++c) rgb.data_[i * colour + c] = data_[i * channels_ + c];
  }
  return rgb;
}

Image ExpandToRgb(const Image& image) {
  const Image colour = image.Rgb();
  if (colour.channels() == 3) return colour;
  Image rgb(image.width(), image.height(), 3, image.encoding());
  for (std::size_t i = 0; i < image.num_pixels(); ++i)
    for (int c = 0; c < 3; ++c) rgb.values()[i * 3 + c] = colour.values()[i];
  return rgb;
}

float SrgbToLinear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

float LinearToSrgb(float v) {
  if (v <= 0.0031308f) return 12.92f * v;
  return 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

namespace {
Image Convert(const Image& image, Encoding target, float (*fn)(float)) {
  Image out = image;
  if (image.encoding() == target) return out;
  // Alpha (the last channel of grey + alpha and RGBA) is not a colour and keeps its value.
  const int colour_channels = image.ColourChannelCount();
  for (std::size_t i = 0; i < image.num_pixels(); ++i) {
    for (int c = 0; c < colour_channels; ++c) {
      float& v = out.values()[i * image.channels() + c];
      v = fn(v);
    }
  }
  out.set_encoding(target);
  return out;
}
}  // namespace

Image ToLinear(const Image& image) { return Convert(image, Encoding::kLinear, SrgbToLinear); }
Image ToSrgb(const Image& image) { return Convert(image, Encoding::kSrgb, LinearToSrgb); }

Image DisplayImageFromBuffer(const float* values, int width, int height, int channels) {
  Image image(width, height, channels, Encoding::kSrgb);
  for (std::size_t i = 0; i < image.size(); ++i)
    image.values()[i] = std::clamp(values[i], 0.0f, 1.0f);
  return image;
}

long FirstNonFinite(const Image& image) {
  const auto& v = image.values();
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) return static_cast<long>(i);
  }
  return -1;
}

}  // namespace hdr4d
