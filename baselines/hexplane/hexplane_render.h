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

// Whether the model renders an LDR image: HexPlane and HDR-HexPlane do; HexPlane* (log-HDR
// colours trained on the HDR alone) has no trained tone mapper, so no LDR output.
bool HasLdrOutput(const HexPlaneModel& m);

// ldr: H x W x 3 (null: not kept; left empty without an LDR output); hdr: H x W x 3 linear radiance for log-HDR models (left
// empty for an LDR model; may be null).
void RenderView(const HexPlaneModel& m, const Camera& camera, float time01, double exposure,
                int image_index, std::vector<float>* ldr, std::vector<float>* hdr);

// The view at several exposures: one march and appearance, then the tone mapper and composite
// per exposure (RayBatch::Reexpose). ldr: one image per exposure (null: none; left empty without
// an LDR output); hdr as RenderView's. Each image equals RenderView's at that exposure.
void RenderBrackets(const HexPlaneModel& m, const Camera& camera, float time01,
                    const std::vector<double>& exposures, int image_index,
                    std::vector<std::vector<float>>* ldr, std::vector<float>* hdr);

// A split's views rendered one by one in any order, each shot (camera and time) once for all its
// exposures: a multi-view test split films every shot at each exposure (hook's mini test split:
// 60 views, 20 shots), so its brackets cost one march and one appearance. Keeps one shot.
class BracketRenderer {
 public:
  struct ViewAt {
    Camera camera;
    float time01 = 0;
    double exposure = 1;
  };
  BracketRenderer(const HexPlaneModel& m, std::vector<ViewAt> views);
  // View `view` of the list, as RenderView would render it (image index -1).
  void Render(std::size_t view, std::vector<float>* ldr, std::vector<float>* hdr);
  int shots_rendered() const { return shots_rendered_; }

 private:
  static bool SameShot(const ViewAt& a, const ViewAt& b);
  const HexPlaneModel& m_;
  std::vector<ViewAt> views_;
  std::vector<std::size_t> shot_views_;  // the views of the shot held
  std::vector<std::vector<float>> shot_ldr_;
  std::vector<float> shot_hdr_;
  int shots_rendered_ = 0;
};

// The test metrics of a Gaussian run's results.json (method/train/test_evaluation.h): LDR
// metrics with FLIP, and where a view has HDR ground truth and the model HDR colours, Table 1's
// HDR metrics, the scale-aligned ones and the HDR's log-log slope.
nlohmann::json EvaluateHexPlane(const HexPlaneModel& m, const std::vector<method::TrainView>& views);

struct HexPlaneRenderOptions {
  std::filesystem::path run, out;  // out: default RUN/renders/<split>
  std::string split = "test";
  int resolution = 0;  // 0: the run's
  std::optional<double> exposure;  // default: each view's own; the median training one for video
  bool write_hdr = true;
  int png_compression = 1;
  // As `hdr4d render` for Gaussian runs (method/run/render_split.h): one view of frame
  // `camera_index` of the split at `time` (default out RUN/renders/time), or `video_frames`
  // frames orbiting the scene while time runs 0..1 (RUN/video, MP4 with ffmpeg); `timing`: a JSON
  // file of each split view's render time and the fps after the first view.
  std::optional<float> time;
  int camera_index = 0;
  int video_frames = 0;
  int fps = 24;
  std::filesystem::path timing;
};

// True when RUN/config.json names a HexPlane method (then `hdr4d render` calls the function
// below instead of the Gaussian renderer).
bool IsHexPlaneRun(const std::filesystem::path& run);
// The grid method RUN/config.json names, or nullopt when RUN is no HexPlane run.
std::optional<std::string> HexPlaneMethodOfRun(const std::filesystem::path& run);
// Returns the number of images written.
int RenderHexPlaneRun(const HexPlaneRenderOptions& options);

}  // namespace hdr4d::baselines::hexplane
