// OpenEXR files through the OpenEXR library (Debian's libopenexr-dev).
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <Imath/half.h>

#include <algorithm>
#include <exception>
#include <string>
#include <vector>

#include "core/image/image_formats.h"
#include "core/util/error.h"

namespace hdr4d::image_formats {
namespace fs = std::filesystem;

namespace {

std::string ExrMessage(const std::exception& e) {
  std::string text = e.what();
  if (const std::size_t end = text.find('\n'); end != std::string::npos) text.resize(end);
  return text.empty() ? "not a readable OpenEXR file" : text;
}

// The channels read, in the order they are stored in the image: R, G, B, A when the file has
// them, else luminance Y (and A), else every channel in the file's (alphabetical) order.
std::vector<std::string> ExrChannelOrder(const Imf::ChannelList& list) {
  std::vector<std::string> order;
  for (const char* name : {"R", "G", "B"})
    if (list.findChannel(name)) order.push_back(name);
  if (order.empty() && list.findChannel("Y")) order.push_back("Y");
  if (!order.empty()) {
    if (list.findChannel("A")) order.push_back("A");
    return order;
  }
  for (auto it = list.begin(); it != list.end(); ++it) order.push_back(it.name());
  return order;
}

}  // namespace

Header ReadExrHeader(const fs::path& path) {
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i window = file.header().dataWindow();
    const int channels = static_cast<int>(ExrChannelOrder(file.header().channels()).size());
    return {window.max.x - window.min.x + 1, window.max.y - window.min.y + 1, channels, true};
  } catch (const std::exception& e) {
    Fail("{}: cannot read image: {}", path.string(), ExrMessage(e));
  }
}

Image ReadExr(const fs::path& path) {
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i window = file.header().dataWindow();
    const int width = window.max.x - window.min.x + 1;
    const int height = window.max.y - window.min.y + 1;
    const std::vector<std::string> order = ExrChannelOrder(file.header().channels());
    if (width <= 0 || height <= 0 || order.empty())
      Fail("{}: image has no pixels ({}x{}x{})", path.string(), width, height, order.size());
    const int channels = static_cast<int>(order.size());
    Image image(width, height, channels, Encoding::kLinear);
    // The slices address the data window's own coordinates, which need not start at (0, 0).
    const std::size_t xs = sizeof(float) * channels, ys = xs * width;
    char* origin = reinterpret_cast<char*>(image.data()) -
                   static_cast<std::ptrdiff_t>(window.min.x * xs + window.min.y * ys);
    Imf::FrameBuffer buffer;
    for (int c = 0; c < channels; ++c)
      buffer.insert(order[c], Imf::Slice(Imf::FLOAT, origin + c * sizeof(float), xs, ys));
    file.setFrameBuffer(buffer);
    file.readPixels(window.min.y, window.max.y);
    return image;
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    Fail("{}: cannot decode image: {}", path.string(), ExrMessage(e));
  }
}

void WriteExr(const fs::path& path, const fs::path& tmp, const Image& image, bool half) {
  static const std::vector<std::vector<const char*>> kNames = {
      {"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
  const int channels = image.channels();
  if (channels < 1 || channels > 4)
    Fail("{}: EXR is written with 1-4 channels, image has {}", path.string(), channels);
  try {
    Imf::Header header(image.width(), image.height());
    header.compression() = Imf::ZIP_COMPRESSION;
    // OpenEXR writes a slice of the file's own pixel type: half values are converted here.
    std::vector<Imath::half> halves;
    if (half) halves.assign(image.values().begin(), image.values().end());
    const std::size_t size = half ? sizeof(Imath::half) : sizeof(float);
    const std::size_t xs = size * channels, ys = xs * image.width();
    char* base = half ? reinterpret_cast<char*>(halves.data())
                      : const_cast<char*>(reinterpret_cast<const char*>(image.data()));
    const Imf::PixelType type = half ? Imf::HALF : Imf::FLOAT;
    Imf::FrameBuffer buffer;
    for (int c = 0; c < channels; ++c) {
      header.channels().insert(kNames[channels - 1][c], Imf::Channel(type));
      buffer.insert(kNames[channels - 1][c], Imf::Slice(type, base + c * size, xs, ys));
    }
    Imf::OutputFile file(tmp.c_str(), header);
    file.setFrameBuffer(buffer);
    file.writePixels(image.height());
  } catch (const std::exception& e) {
    Fail("{}: write failed: {}", path.string(), ExrMessage(e));
  }
}

}  // namespace hdr4d::image_formats
