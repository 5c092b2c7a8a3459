#include "benchmark/report_images.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/metrics/metrics.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;
namespace {

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) Fail("{}: cannot read", path.string());
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A temporary file name in the system temp folder, removed with the object.
class TempFile {
 public:
  explicit TempFile(const std::string& extension) {
    static std::atomic<int> counter{0};
    path_ = fs::temp_directory_path() /
            ("hdr4d-report-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + extension);
  }
  ~TempFile() {
    std::error_code ec;
    fs::remove(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

}  // namespace

std::string Base64(const std::string& bytes) {
  static const char* kTable = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t b0 = static_cast<unsigned char>(bytes[i]);
    const std::uint32_t b1 = i + 1 < bytes.size() ? static_cast<unsigned char>(bytes[i + 1]) : 0;
    const std::uint32_t b2 = i + 2 < bytes.size() ? static_cast<unsigned char>(bytes[i + 2]) : 0;
    const std::uint32_t v = (b0 << 16) | (b1 << 8) | b2;
    out.push_back(kTable[(v >> 18) & 63]);
    out.push_back(kTable[(v >> 12) & 63]);
    out.push_back(i + 1 < bytes.size() ? kTable[(v >> 6) & 63] : '=');
    out.push_back(i + 2 < bytes.size() ? kTable[v & 63] : '=');
  }
  return out;
}

std::string PngDataUri(const Image& image) {
  TempFile file(".png");
  Image display = image;
  display.set_encoding(Encoding::kSrgb);  // values are written as they are
  WriteImage(file.path(), display);
  return "data:image/png;base64," + Base64(ReadBytes(file.path()));
}

std::string FileDataUri(const fs::path& path) {
  const std::string type = path.extension() == ".svg" ? "image/svg+xml" : "image/png";
  return "data:" + type + ";base64," + Base64(ReadBytes(path));
}

std::string SvgDataUri(const std::string& svg) { return "data:image/svg+xml;base64," + Base64(svg); }

std::string PlotDataUri(const std::vector<PlotSeries>& series, const PlotOptions& options) {
  return SvgDataUri(RenderPlotSvg(series, options));
}

std::string PlotGridDataUri(const std::vector<PlotPanel>& panels, int columns) {
  return SvgDataUri(RenderPlotGridSvg(panels, columns));
}

Image MuLawDisplay(const Image& hdr) {
  Image rgb = hdr.Rgb();
  const float max = rgb.MaxValue();
  for (float& v : rgb.values()) v = max > 0 ? std::clamp(v / max, 0.0f, 1.0f) : 0.0f;
  Image out = MuLaw(rgb);
  out.set_encoding(Encoding::kSrgb);
  return out;
}

Image ErrorMap(const Image& a, const Image& b, double full_scale) {
  if (!a.SameShape(b)) Fail("error map: images differ in shape ({} vs {})", a.ShapeString(), b.ShapeString());
  Image out(a.width(), a.height(), 3, Encoding::kSrgb);
  const int c = std::min(a.channels(), 3);
  for (int y = 0; y < a.height(); ++y) {
    for (int x = 0; x < a.width(); ++x) {
      double e = 0;
      for (int k = 0; k < c; ++k) e += std::abs(a.at(x, y, k) - b.at(x, y, k));
      const double t = std::clamp(e / c / full_scale, 0.0, 1.0);
      // black -> red -> yellow -> white, thirds of the range each.
      out.at(x, y, 0) = static_cast<float>(std::min(1.0, 3 * t));
      out.at(x, y, 1) = static_cast<float>(std::clamp(3 * t - 1, 0.0, 1.0));
      out.at(x, y, 2) = static_cast<float>(std::clamp(3 * t - 2, 0.0, 1.0));
    }
  }
  return out;
}

Image WithBox(const Image& image, const std::array<double, 4>& box, const std::array<float, 3>& rgb) {
  Image out = image.Rgb();
  const int x0 = static_cast<int>(box[0] * out.width()), y0 = static_cast<int>(box[1] * out.height());
  const int x1 = std::min(out.width() - 1, static_cast<int>((box[0] + box[2]) * out.width()) - 1);
  const int y1 = std::min(out.height() - 1, static_cast<int>((box[1] + box[3]) * out.height()) - 1);
  for (int x = x0; x <= x1; ++x)
    for (int k = 0; k < 3; ++k) out.at(x, y0, k) = out.at(x, y1, k) = rgb[k];
  for (int y = y0; y <= y1; ++y)
    for (int k = 0; k < 3; ++k) out.at(x0, y, k) = out.at(x1, y, k) = rgb[k];
  return out;
}

}  // namespace hdr4d::bench
