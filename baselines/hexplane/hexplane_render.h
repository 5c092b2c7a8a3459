// Images of a HexPlane model: one view rendered ray by ray, a split's test metrics, and
// `hdr4d render` for a HexPlane run folder (the files named like their ground truth, as the
// Gaussian runs' renders, so `hdr4d eval` scores them the same way).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "baselines/hexplane/hexplane_model.h"
#include "baselines/hexplane/ray_batch.h"
#include "core/geometry/camera.h"
#include "method/train/train_views.h"

namespace hdr4d::baselines::hexplane {

// The ray of pixel (x, y) (its centre) of `camera` at normalised time `time01` in [0, 1].
Ray PixelRay(const Camera& camera, int x, int y, float time01, float log_exposure, int image);

// ldr: H x W x 3 (null: not kept); hdr: H x W x 3 linear radiance for log-HDR models (left
// empty for an LDR model; may be null).
void RenderView(const HexPlaneModel& m, const Camera& camera, float time01, double exposure,
                int image_index, std::vector<float>* ldr, std::vector<float>* hdr);

// Mean LDR metrics (hdr4d eval's keys) of the final LDR renders over `views`, plus the HDR
// metrics where a view has HDR ground truth and the model HDR colours.
nlohmann::json EvaluateHexPlane(const HexPlaneModel& m, const std::vector<method::TrainView>& views);

struct HexPlaneRenderOptions {
  std::filesystem::path run, out;  // out: default RUN/renders/<split>
  std::string split = "test";
  int resolution = 0;  // 0: the run's
  std::optional<double> exposure;
  bool write_hdr = true;
  int png_compression = 1;
};

// True when RUN/config.json names a HexPlane method (then `hdr4d render` calls the function
// below instead of the Gaussian renderer).
bool IsHexPlaneRun(const std::filesystem::path& run);
// Returns the number of images written.
int RenderHexPlaneRun(const HexPlaneRenderOptions& options);

}  // namespace hdr4d::baselines::hexplane
