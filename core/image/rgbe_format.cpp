// Radiance RGBE (.hdr) files, read here: the format is a text header and run-length-coded
// scanlines of four bytes per pixel (mantissas and a shared exponent; Greg Ward, Graphics Gems
// II, 1991). Only the standard orientation (-Y height +X width) is accepted.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "core/image/image_formats.h"
#include "core/util/error.h"

namespace hdr4d::image_formats {
namespace fs = std::filesystem;

namespace {

// Reads the header up to and including the resolution line; the stream is left at the pixels.
Header ReadRgbeHeaderFrom(const fs::path& path, std::istream& in) {
  std::string line;
  if (!std::getline(in, line) || line.rfind("#?", 0) != 0)
    Fail("{}: cannot read image: not a Radiance HDR file", path.string());
  bool rgbe = true;
  while (std::getline(in, line) && !line.empty())
    if (line.rfind("FORMAT=", 0) == 0) rgbe = line == "FORMAT=32-bit_rle_rgbe";
  if (!rgbe) Fail("{}: cannot read image: Radiance HDR in a format other than RGBE", path.string());
  int width = 0, height = 0;
  char y_axis[3] = "", x_axis[3] = "";
  if (!std::getline(in, line) ||
      std::sscanf(line.c_str(), "%2s %d %2s %d", y_axis, &height, x_axis, &width) != 4)
    Fail("{}: cannot read image: Radiance HDR without a resolution line", path.string());
  if (std::string(y_axis) != "-Y" || std::string(x_axis) != "+X")
    Fail("{}: cannot read image: Radiance HDR orientation '{}' (only -Y H +X W)", path.string(),
         line);
  if (width <= 0 || height <= 0 || width > (1 << 16) || height > (1 << 16))
    Fail("{}: cannot read image: Radiance HDR size {}x{}", path.string(), width, height);
  return {width, height, 3, true};
}

// One scanline of `width` RGBE pixels: the run-length form (each of the four components coded
// separately) when the line starts with 2, 2 and its width, else flat pixels.
bool ReadRgbeScanline(std::istream& in, int width, unsigned char* out) {
  unsigned char head[4];
  if (!in.read(reinterpret_cast<char*>(head), 4)) return false;
  const bool rle = width >= 8 && width < 32768 && head[0] == 2 && head[1] == 2 &&
                   ((head[2] << 8) | head[3]) == width;
  if (!rle) {
    for (int k = 0; k < 4; ++k) out[k] = head[k];
    return static_cast<bool>(in.read(reinterpret_cast<char*>(out + 4), 4 * (width - 1)));
  }
  for (int c = 0; c < 4; ++c) {
    for (int x = 0; x < width;) {
      int count = in.get();
      if (count <= 0) return false;  // EOF, or a zero-length run (corrupt)
      if (count > 128) {
        count -= 128;
        const int value = in.get();
        if (value < 0 || x + count > width) return false;
        for (int k = 0; k < count; ++k) out[4 * (x++) + c] = static_cast<unsigned char>(value);
      } else {
        if (x + count > width) return false;
        for (int k = 0; k < count; ++k) {
          const int value = in.get();
          if (value < 0) return false;
          out[4 * (x++) + c] = static_cast<unsigned char>(value);
        }
      }
    }
  }
  return true;
}

std::ifstream OpenRgbe(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) Fail("{}: cannot open", path.string());
  return in;
}

}  // namespace

Header ReadRgbeHeader(const fs::path& path) {
  std::ifstream in = OpenRgbe(path);
  return ReadRgbeHeaderFrom(path, in);
}

Image ReadRgbe(const fs::path& path) {
  std::ifstream in = OpenRgbe(path);
  const Header h = ReadRgbeHeaderFrom(path, in);
  Image image(h.width, h.height, 3, Encoding::kLinear);
  std::vector<unsigned char> line(4 * static_cast<std::size_t>(h.width));
  for (int y = 0; y < h.height; ++y) {
    if (!ReadRgbeScanline(in, h.width, line.data()))
      Fail("{}: cannot decode image: truncated or corrupt scanline {}", path.string(), y);
    float* row = image.data() + static_cast<std::size_t>(y) * h.width * 3;
    for (int x = 0; x < h.width; ++x) {
      const unsigned char* p = &line[4 * x];
      // Value = (mantissa + 0.5) / 256 * 2^(exponent - 128); exponent 0 is black.
      const float scale = p[3] == 0 ? 0.0f : std::ldexp(1.0f, p[3] - 136);
      for (int c = 0; c < 3; ++c) row[3 * x + c] = p[3] == 0 ? 0.0f : (p[c] + 0.5f) * scale;
    }
  }
  return image;
}

}  // namespace hdr4d::image_formats
