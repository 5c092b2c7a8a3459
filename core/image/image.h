// A float image with any number of interleaved channels. Whether the values are linear
// radiance or display-encoded (sRGB) is part of the image, so no code has to guess.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace hdr4d {

// How the pixel values relate to light.
enum class Encoding {
  kLinear,  // proportional to radiance (EXR, HDR renders, linear LDR after the inverse CRF)
  kSrgb,    // display-encoded in [0,1] (8/16-bit PNG and JPEG as stored on disk)
};

const char* EncodingName(Encoding encoding);

class Image {
 public:
  Image() = default;
  Image(int width,
        int height,
        int channels,
        Encoding encoding = Encoding::kLinear,
        float fill = 0.0f);

  int width() const { return width_; }
  int height() const { return height_; }
  int channels() const { return channels_; }
  Encoding encoding() const { return encoding_; }
  void set_encoding(Encoding encoding) { encoding_ = encoding; }
  bool empty() const { return data_.empty(); }
  std::size_t num_pixels() const { return static_cast<std::size_t>(width_) * height_; }
  std::size_t size() const { return data_.size(); }

  // Interleaved: index = (y * width + x) * channels + c.
  float& at(int x, int y, int c) { return data_[Index(x, y, c)]; }
  float at(int x, int y, int c) const { return data_[Index(x, y, c)]; }
  float* data() { return data_.data(); }
  const float* data() const { return data_.data(); }
  std::vector<float>& values() { return data_; }
  const std::vector<float>& values() const { return data_; }

  bool SameShape(const Image& other) const {
    return width_ == other.width_ && height_ == other.height_ && channels_ == other.channels_;
  }
  std::string ShapeString() const;  // "WxHxC"

  float MaxValue() const;
  // The colour channels without alpha (ColourChannelCount): RGB of RGB / RGBA, grey of grey /
  // grey + alpha; throws if the image has no channels.
  Image Rgb() const;
  // Alpha is the last channel of grey + alpha (2) and RGBA (4): the others are colour.
  int ColourChannelCount() const { return channels_ == 2 ? 1 : channels_ >= 4 ? 3 : channels_; }

 private:
  std::size_t Index(int x, int y, int c) const {
    return (static_cast<std::size_t>(y) * width_ + x) * channels_ + c;
  }

  int width_ = 0;
  int height_ = 0;
  int channels_ = 0;
  Encoding encoding_ = Encoding::kLinear;
  std::vector<float> data_;
};

// The sRGB transfer functions (IEC 61966-2-1), per value.
float SrgbToLinear(float encoded);
float LinearToSrgb(float linear);
// Whole-image conversions; converting an image already in the target encoding is a no-op copy.
Image ToLinear(const Image& image);
Image ToSrgb(const Image& image);

// Three colour channels whatever the image has: grey (and grey + alpha) repeated, alpha dropped.
Image ExpandToRgb(const Image& image);

// A rendered buffer (H x W x channels floats) as a display image: values clamped to [0,1],
// tagged as display-encoded (what LDR renders are written and scored as).
Image DisplayImageFromBuffer(const float* values, int width, int height, int channels);

// Index of the first NaN or Inf value, or -1 when all are finite.
long FirstNonFinite(const Image& image);

}  // namespace hdr4d
