#include "method/train_views.h"

#include <cmath>

#include "core/error.h"
#include "core/image_io.h"
#include "core/parallel.h"

namespace hdr4d::method {

void TrainView::ToFloat(std::vector<float>* out) const {
  out->resize(rgb.size());
  constexpr float kScale = 1.0f / 255.0f;
  for (std::size_t i = 0; i < rgb.size(); ++i) (*out)[i] = rgb[i] * kScale;
}

std::vector<TrainView> LoadViews(const Dataset& dataset, Split split, const float background[3]) {
  const std::vector<Frame>& frames = dataset.FramesOf(split);
  std::vector<TrainView> views(frames.size());
  ParallelFor(static_cast<std::int64_t>(frames.size()), 1, [&](std::int64_t i) {
    const Frame& f = frames[i];
    const Image image = ReadImage(f.image_path);
    if (image.encoding() != Encoding::kSrgb) {
      Fail("{}: training targets are LDR images (PNG/JPEG); this one is linear HDR",
           f.image_path.string());
    }
    if (image.width() != f.camera.intrinsics.width ||
        image.height() != f.camera.intrinsics.height) {
      Fail("{}: image is {}x{} but the camera says {}x{}", f.image_path.string(), image.width(),
           image.height(), f.camera.intrinsics.width, f.camera.intrinsics.height);
    }
    if (image.channels() < 3 && image.channels() != 1) {
      Fail("{}: expected RGB, RGBA or grey, got {} channels", f.image_path.string(),
           image.channels());
    }
    TrainView& v = views[i];
    v.camera = f.camera;
    v.time = static_cast<float>(f.time);
    v.exposure = f.exposure;
    v.name = f.image_path.filename().string();
    v.rgb.resize(image.num_pixels() * 3);
    const int c = image.channels();
    for (std::size_t p = 0; p < image.num_pixels(); ++p) {
      const float* px = image.data() + p * c;
      const float alpha = c == 4 ? px[3] : 1.0f;
      for (int k = 0; k < 3; ++k) {
        const float value = (c == 1 ? px[0] : px[k]) * alpha + background[k] * (1.0f - alpha);
        v.rgb[p * 3 + k] =
            static_cast<std::uint8_t>(std::lround(std::clamp(value, 0.0f, 1.0f) * 255.0f));
      }
    }
  });
  return views;
}

}  // namespace hdr4d::method
