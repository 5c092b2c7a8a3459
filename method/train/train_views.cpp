#include "method/train/train_views.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/dataset/dataset_image_rules.h"
#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/image/image_resize.h"
#include "core/util/parallel.h"
#include "method/train/hdr_loss.h"

namespace hdr4d::method {

namespace {

// One LDR frame as the views keep it: read, checked (an integer LDR image of the camera's size,
// divisible by the resolution; else hdr4d::Error naming the file), composited over `background`
// at full size, then box-averaged in the stored (display) encoding, as the reference composites
// and then resizes the 8-bit image with PIL.
std::vector<std::uint8_t> ReadViewPixels(const std::filesystem::path& path,
                                         int width,
                                         int height,
                                         const std::array<float, 3>& background,
                                         int resolution) {
  const Image image = ReadImage(path);
  if (std::string problem = LdrImageProblem(image); !problem.empty())
    Fail("{}: {}", path.string(), problem);
  if (image.width() != width || image.height() != height) {
    Fail("{}: image is {}x{} but the camera says {}x{}", path.string(), image.width(),
         image.height(), width, height);
  }
  if (std::string problem = ResolutionProblem(image.width(), image.height(), resolution);
      !problem.empty())
    Fail("{}: {}", path.string(), problem);
  Image rgb(image.width(), image.height(), 3, image.encoding());
  const int c = image.channels();
  for (std::size_t p = 0; p < image.num_pixels(); ++p) {
    const float* px = image.data() + p * c;
    const float alpha = c == 4 || c == 2 ? px[c - 1] : 1.0f;  // RGBA, grey + alpha
    for (int k = 0; k < 3; ++k)
      rgb.data()[p * 3 + k] = (c <= 2 ? px[0] : px[k]) * alpha + background[k] * (1.0f - alpha);
  }
  const Image reduced = DownsampleBox(rgb, resolution);
  std::vector<std::uint8_t> out(reduced.size());
  for (std::size_t p = 0; p < reduced.size(); ++p)
    out[p] = static_cast<std::uint8_t>(
        std::lround(std::clamp(reduced.data()[p], 0.0f, 1.0f) * 255.0f));
  return out;
}

// out = in x scale as floats: a view's stored target on every step, in parallel chunks (a
// serial pass left the other threads idle).
template <typename T>
void ScaledToFloats(const std::vector<T>& in, float scale, std::vector<float>* out) {
  constexpr std::int64_t kGrain = 1 << 16;
  out->resize(in.size());
  float* to = out->data();
  ParallelForChunks(static_cast<std::int64_t>(in.size()), kGrain,
                    [&](std::int64_t b, std::int64_t e) {
                      for (std::int64_t i = b; i < e; ++i) to[i] = in[i] * scale;
                    });
}

}  // namespace

void TrainView::ToFloat(std::vector<float>* out) const {
  std::vector<std::uint8_t> read;
  if (rgb.empty()) {
    read = ReadViewPixels(image_path, width() * resolution, height() * resolution, background,
                          resolution);
  }
  const std::vector<std::uint8_t>& pixels = rgb.empty() ? read : rgb;
  ScaledToFloats(pixels, 1.0f / 255.0f, out);
}

void TrainView::HdrMuToFloat(std::vector<float>* out) const {
  HDR4D_CHECK(!hdr_mu.empty());
  ScaledToFloats(hdr_mu, 1.0f / 65535.0f, out);
}

namespace {

float MaxRgb(const Image& hdr) {
  const int c = hdr.channels();
  float max_value = 0;
  for (std::size_t p = 0; p < hdr.num_pixels(); ++p)
    for (int k = 0; k < 3; ++k) max_value = std::max(max_value, hdr.data()[p * c + k]);
  return max_value;
}

// The HDR target of the training loss, 16 bits per value: mu(gt / divisor), the image's own
// maximum when divisor is 0. At `resolution` the radiance is box-averaged (linear light: the
// mean a pixel R times larger would integrate) before the maximum and the mu-law.
std::vector<std::uint16_t> LoadHdrMuTarget(const std::filesystem::path& path,
                                           int width,
                                           int height,
                                           int resolution,
                                           float divisor,
                                           double mu_law) {
  // The dataset's rules for HDR ground truth (`dataset check` applies the same ones): linear,
  // RGB, finite, non-negative, some light.
  const Image full = ReadHdrGroundTruth(path);
  if (full.width() != width || full.height() != height) {
    Fail("{}: HDR ground truth is {}x{} but the LDR image is {}x{}", path.string(), full.width(),
         full.height(), width, height);
  }
  const Image hdr = DownsampleBox(full, resolution);
  const int c = hdr.channels();
  const float max_value = divisor > 0 ? divisor : MaxRgb(hdr);
  std::vector<std::uint16_t> mu(hdr.num_pixels() * 3);
  for (std::size_t p = 0; p < hdr.num_pixels(); ++p) {
    for (int k = 0; k < 3; ++k) {
      const float v = MuLawEncode(hdr.data()[p * c + k] / max_value, mu_law);
      mu[p * 3 + k] = static_cast<std::uint16_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 65535.0f));
    }
  }
  return mu;
}

}  // namespace

std::optional<float> MedianLogHdrTarget(const std::vector<TrainView>& views, double mu_law) {
  // A regular sample of at most ~1e6 values (a paper-size scene has 1e8), its stride prime to
  // 3 so that every channel is sampled.
  std::size_t total = 0;
  for (const TrainView& v : views) total += v.hdr_mu.size();
  std::size_t stride = std::max<std::size_t>(7, total / 1'000'000);
  if (stride % 3 == 0) ++stride;
  std::vector<float> logs;
  for (const TrainView& v : views) {
    for (std::size_t i = 0; i < v.hdr_mu.size(); i += stride) {
      if (v.hdr_mu[i] == 0) continue;  // below the 16-bit target's first step: no level
      logs.push_back(static_cast<float>(std::log(MuLawDecode(v.hdr_mu[i] / 65535.0, mu_law))));
    }
  }
  if (logs.empty()) return std::nullopt;
  auto mid = logs.begin() + static_cast<std::ptrdiff_t>(logs.size() / 2);
  std::nth_element(logs.begin(), mid, logs.end());
  return *mid;
}

PinholeIntrinsics DownscaledIntrinsics(const PinholeIntrinsics& intrinsics, int factor) {
  HDR4D_CHECK(factor >= 1 && intrinsics.width % factor == 0 && intrinsics.height % factor == 0);
  PinholeIntrinsics k = intrinsics;
  k.fx /= factor;
  k.fy /= factor;
  k.cx /= factor;
  k.cy /= factor;
  k.width /= factor;
  k.height /= factor;
  return k;
}

namespace {

std::vector<TrainView> ReadViews(const Dataset& dataset,
                                 Split split,
                                 const float background[3],
                                 bool load_hdr,
                                 int resolution,
                                 HdrTarget target,
                                 bool keep_pixels) {
  if (resolution < 1) Fail("train: --resolution {} must be >= 1", resolution);
  const std::vector<Frame>& frames = dataset.FramesOf(split);
  std::vector<TrainView> views(frames.size());
  // scene-log: one divisor, the largest value of the split's HDR ground truth (a first pass).
  float divisor = 0;
  if (load_hdr && target == HdrTarget::kSceneLog) {
    std::vector<float> maxima(frames.size(), 0.0f);
    ParallelFor(static_cast<std::int64_t>(frames.size()), 1, [&](std::int64_t i) {
      if (frames[i].hdr_path)
        maxima[i] = MaxRgb(DownsampleBox(ReadHdrGroundTruth(*frames[i].hdr_path), resolution));
    });
    for (float m : maxima) divisor = std::max(divisor, m);
  }
  ParallelFor(static_cast<std::int64_t>(frames.size()), 1, [&](std::int64_t i) {
    const Frame& f = frames[i];
    TrainView& v = views[i];
    v.image_path = f.image_path;
    v.resolution = resolution;
    v.background = {background[0], background[1], background[2]};
    std::vector<std::uint8_t> pixels = ReadViewPixels(
        f.image_path, f.camera.intrinsics.width, f.camera.intrinsics.height, v.background,
        resolution);
    if (keep_pixels) v.rgb = std::move(pixels);
    v.camera = f.camera;
    v.camera.intrinsics = DownscaledIntrinsics(f.camera.intrinsics, resolution);
    v.time = static_cast<float>(f.time);
    v.exposure = f.exposure;
    v.name = f.image_path.filename().string();
    v.image_index = static_cast<int>(i);
    v.hdr_path = f.hdr_path;
    if (load_hdr && f.hdr_path) {
      v.hdr_mu = LoadHdrMuTarget(*f.hdr_path, f.camera.intrinsics.width,
                                 f.camera.intrinsics.height, resolution, divisor,
                                 HdrTargetMu(target));
    }
  });
  return views;
}

}  // namespace

std::vector<TrainView> LoadViews(const Dataset& dataset,
                                 Split split,
                                 const float background[3],
                                 bool load_hdr,
                                 int resolution,
                                 HdrTarget target) {
  return ReadViews(dataset, split, background, load_hdr, resolution, target, true);
}

std::vector<TrainView> CheckViews(const Dataset& dataset,
                                  Split split,
                                  const float background[3],
                                  int resolution) {
  return ReadViews(dataset, split, background, false, resolution, HdrTarget::kImageMax, false);
}

}  // namespace hdr4d::method
