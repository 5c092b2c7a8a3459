#include "baselines/hexplane/hexplane_render.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "core/files/atomic_file.h"
#include "core/files/json_util.h"
#include "core/files/output_guard.h"
#include "core/image/image_io.h"
#include "core/metrics/metrics.h"
#include "method/train/test_evaluation.h"
#include "core/util/error.h"
#include "core/util/progress.h"

namespace hdr4d::baselines::hexplane {
namespace fs = std::filesystem;

Ray PixelRay(const Camera& camera, int x, int y, float time01, float log_exposure, int image) {
  const Eigen::Vector3d o = camera.Center();
  const Eigen::Vector3d d = (camera.Unproject(x + 0.5, y + 0.5, 1.0) - o).normalized();
  Ray r;
  for (int a = 0; a < 3; ++a) {
    r.origin[a] = float(o[a]);
    r.dir[a] = float(d[a]);
  }
  r.time = 2.0f * time01 - 1.0f;  // the reference maps D-NeRF's [0, 1] onto the grid's [-1, 1]
  r.log_exposure = log_exposure;
  r.image = image;
  return r;
}

bool HasLdrOutput(const HexPlaneModel& m) {
  return m.config.color == ColorModel::kLdr || m.config.ldr_loss;
}

void RenderView(const HexPlaneModel& m, const Camera& camera, float time01, double exposure,
                int image_index, std::vector<float>* ldr, std::vector<float>* hdr) {
  const int w = camera.intrinsics.width, h = camera.intrinsics.height, K = RayChannels(m);
  const float log_exposure = float(std::log(std::max(exposure, 1e-30)));
  if (ldr && !HasLdrOutput(m)) {
    ldr->clear();
    ldr = nullptr;
  }
  if (ldr) ldr->assign(std::size_t(w) * h * 3, 0.0f);
  if (hdr) hdr->assign(K == 6 ? std::size_t(w) * h * 3 : 0, 0.0f);
  constexpr int kChunk = 8192;  // rays per batch: bounded memory whatever the image size
  RayBatch batch;
  std::vector<Ray> rays;
  std::vector<float> out;
  for (std::int64_t begin = 0; begin < std::int64_t(w) * h; begin += kChunk) {
    const std::int64_t end = std::min<std::int64_t>(begin + kChunk, std::int64_t(w) * h);
    rays.clear();
    for (std::int64_t p = begin; p < end; ++p)
      rays.push_back(PixelRay(camera, int(p % w), int(p / w), time01, log_exposure, image_index));
    batch.Forward(m, rays, nullptr, &out);
    for (std::int64_t p = begin; p < end; ++p)
      for (int k = 0; k < 3; ++k) {
        const float* o = &out[std::size_t(p - begin) * K];
        if (ldr) (*ldr)[std::size_t(p) * 3 + k] = std::clamp(o[k], 0.0f, 1.0f);
        if (hdr && K == 6) (*hdr)[std::size_t(p) * 3 + k] = o[3 + k];
      }
  }
}

nlohmann::json EvaluateHexPlane(const HexPlaneModel& m, const std::vector<method::TrainView>& views) {
  return method::EvaluateViews(
      [&m](const method::TrainView& v, std::vector<float>* ldr, std::vector<float>* hdr) {
        RenderView(m, v.camera, v.time, v.exposure, -1, ldr, hdr);
      },
      views);
}

}  // namespace hdr4d::baselines::hexplane
