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

void RenderBrackets(const HexPlaneModel& m, const Camera& camera, float time01,
                    const std::vector<double>& exposures, int image_index,
                    std::vector<std::vector<float>>* ldr, std::vector<float>* hdr) {
  const int w = camera.intrinsics.width, h = camera.intrinsics.height, K = RayChannels(m);
  const std::size_t pixels = std::size_t(w) * h;
  if (ldr && !HasLdrOutput(m)) {
    ldr->clear();
    ldr = nullptr;
  }
  if (hdr) hdr->assign(K == 6 ? pixels * 3 : 0, 0.0f);
  if (ldr) ldr->assign(exposures.size(), std::vector<float>(pixels * 3, 0.0f));
  if (exposures.empty()) ldr = nullptr;
  if (!ldr && (!hdr || hdr->empty())) return;  // nothing asked for
  std::vector<float> log_exposures;
  for (double t : exposures) log_exposures.push_back(float(std::log(std::max(t, 1e-30))));
  if (log_exposures.empty()) log_exposures.push_back(0.0f);  // the HDR alone
  constexpr int kChunk = 8192;  // rays per batch: bounded memory whatever the image size
  RayBatch batch;
  std::vector<Ray> rays;
  std::vector<float> out;
  for (std::int64_t begin = 0; begin < std::int64_t(pixels); begin += kChunk) {
    const std::int64_t end = std::min<std::int64_t>(begin + kChunk, std::int64_t(pixels));
    rays.clear();
    for (std::int64_t p = begin; p < end; ++p)
      rays.push_back(PixelRay(camera, int(p % w), int(p / w), time01, log_exposures[0], image_index));
    for (std::size_t e = 0; e < log_exposures.size(); ++e) {
      if (e == 0) {
        batch.Forward(m, rays, nullptr, &out);
      } else {
        for (Ray& r : rays) r.log_exposure = log_exposures[e];
        batch.Reexpose(m, rays, &out);
      }
      for (std::int64_t p = begin; p < end; ++p)
        for (int k = 0; k < 3; ++k) {
          const float* o = &out[std::size_t(p - begin) * K];
          if (ldr) (*ldr)[e][std::size_t(p) * 3 + k] = std::clamp(o[k], 0.0f, 1.0f);
          if (e == 0 && hdr && K == 6) (*hdr)[std::size_t(p) * 3 + k] = o[3 + k];
        }
      if (!ldr) break;  // the HDR does not depend on the exposure
    }
  }
}

void RenderView(const HexPlaneModel& m, const Camera& camera, float time01, double exposure,
                int image_index, std::vector<float>* ldr, std::vector<float>* hdr) {
  std::vector<std::vector<float>> brackets;
  RenderBrackets(m, camera, time01, {exposure}, image_index, ldr ? &brackets : nullptr, hdr);
  if (!ldr) return;
  if (brackets.empty()) {
    ldr->clear();
  } else {
    *ldr = std::move(brackets[0]);
  }
}

BracketRenderer::BracketRenderer(const HexPlaneModel& m, std::vector<ViewAt> views)
    : m_(m), views_(std::move(views)) {}

bool BracketRenderer::SameShot(const ViewAt& a, const ViewAt& b) {
  return a.time01 == b.time01 && a.camera.intrinsics == b.camera.intrinsics &&
         a.camera.world_from_cam_gl == b.camera.world_from_cam_gl;
}

void BracketRenderer::Render(std::size_t view, std::vector<float>* ldr, std::vector<float>* hdr) {
  if (view >= views_.size()) Fail("hexplane: view {} of a split of {}", view, views_.size());
  auto held = std::find(shot_views_.begin(), shot_views_.end(), view);
  if (held == shot_views_.end()) {
    shot_views_.clear();
    std::vector<double> exposures;
    for (std::size_t j = 0; j < views_.size(); ++j)
      if (SameShot(views_[j], views_[view])) {
        shot_views_.push_back(j);
        exposures.push_back(views_[j].exposure);
      }
    RenderBrackets(m_, views_[view].camera, views_[view].time01, exposures, -1, &shot_ldr_,
                   &shot_hdr_);
    ++shots_rendered_;
    held = std::find(shot_views_.begin(), shot_views_.end(), view);
  }
  const std::size_t k = std::size_t(held - shot_views_.begin());
  if (ldr) {
    if (shot_ldr_.empty()) {
      ldr->clear();
    } else {
      *ldr = shot_ldr_[k];
    }
  }
  if (hdr) *hdr = shot_hdr_;
}

nlohmann::json EvaluateHexPlane(const HexPlaneModel& m, const std::vector<method::TrainView>& views) {
  std::vector<BracketRenderer::ViewAt> at;
  for (const method::TrainView& v : views) at.push_back({v.camera, v.time, v.exposure});
  BracketRenderer renderer(m, std::move(at));
  return method::EvaluateViews(
      [&](const method::TrainView& v, std::vector<float>* ldr, std::vector<float>* hdr) {
        renderer.Render(std::size_t(&v - views.data()), ldr, hdr);
      },
      views);
}

}  // namespace hdr4d::baselines::hexplane
