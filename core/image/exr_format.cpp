// OpenEXR files through the OpenEXR library (Debian's libopenexr-dev).
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <Imath/half.h>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <map>
#include <set>
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

// A channel's name without its layer ("ViewLayer.Combined.R" -> "R"), upper-cased: Blender's
// multilayer files and some tools write layer-prefixed or lower-case colour channels.
std::string BaseName(const std::string& name) {
  std::string base = name.substr(name.find_last_of('.') + 1);
  for (char& c : base) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return base;
}

// The layer a channel belongs to ("ViewLayer.Combined" for "ViewLayer.Combined.R"; "" for "R").
std::string LayerOf(const std::string& name) {
  const std::size_t dot = name.find_last_of('.');
  return dot == std::string::npos ? "" : name.substr(0, dot);
}

// The file's channel names for R, G, B (and A) of one layer, or Y (and A); empty when the layer
// has neither.
std::vector<std::string> ColourChannels(const Imf::ChannelList& list, const std::string& layer) {
  std::map<std::string, std::string> by_base;  // "R" -> the file's name for it
  for (auto it = list.begin(); it != list.end(); ++it)
    if (LayerOf(it.name()) == layer) by_base.emplace(BaseName(it.name()), it.name());
  std::vector<std::string> order;
  const bool rgb = by_base.count("R") && by_base.count("G") && by_base.count("B");
  if (rgb) order = {by_base["R"], by_base["G"], by_base["B"]};
  else if (by_base.count("Y") && !by_base.count("RY") && !by_base.count("BY"))
    order = {by_base["Y"]};
  if (!order.empty() && by_base.count("A")) order.push_back(by_base["A"]);
  return order;
}

// The channels read, in the order they are stored in the image: R, G, B, A when the file has
// them, else luminance Y (and A). Names are matched without case and layer: the unprefixed
// layer first, else the one layer that has them (a file with several, such as a Blender
// multilayer file with passes, reads its "Combined" layer, else is refused). A file with one
// channel of another name reads it as grey. Anything else is refused: reading other channels
// in the file's (alphabetical) order would swap colours silently.
std::vector<std::string> ExrChannelOrder(const Imf::ChannelList& list, const fs::path& path) {
  std::set<std::string> layers;
  std::vector<std::string> names;
  for (auto it = list.begin(); it != list.end(); ++it) {
    layers.insert(LayerOf(it.name()));
    names.push_back(it.name());
  }
  if (std::vector<std::string> order = ColourChannels(list, ""); !order.empty()) return order;
  std::vector<std::string> colour_layers;
  for (const std::string& layer : layers)
    if (!layer.empty() && !ColourChannels(list, layer).empty()) colour_layers.push_back(layer);
  if (colour_layers.size() > 1) {
    const auto is_combined = [](const std::string& l) { return BaseName(l) == "COMBINED"; };
    const auto combined = std::find_if(colour_layers.begin(), colour_layers.end(), is_combined);
    if (combined == colour_layers.end())
      Fail("{}: several layers hold colour channels ({}); save the one to use as R, G, B",
           path.string(), fmt::join(colour_layers, ", "));
    colour_layers = {*combined};
  }
  if (colour_layers.size() == 1) return ColourChannels(list, colour_layers[0]);
  if (names.size() == 1) return names;
  Fail("{}: no R, G, B or Y channels to read as an image (channels: {})", path.string(),
       fmt::join(names, ", "));
}
}  // namespace

Header ReadExrHeader(const fs::path& path) {
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i window = file.header().dataWindow();
    const int channels = static_cast<int>(ExrChannelOrder(file.header().channels(), path).size());
    return {window.max.x - window.min.x + 1, window.max.y - window.min.y + 1, channels, true};
  } catch (const Error&) {
    throw;
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
    const std::vector<std::string> order = ExrChannelOrder(file.header().channels(), path);
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
