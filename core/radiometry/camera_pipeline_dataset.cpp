#include "core/radiometry/camera_pipeline_dataset.h"

#include <cmath>

#include "core/dataset/dataset_image_rules.h"
#include "core/util/error.h"
#include "core/util/parallel.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

// camera_id where the JSON gives it; otherwise the order of first appearance of each distinct
// pose, offset past every given id so the two kinds never collide.
std::vector<int> CameraNumbers(const std::vector<const Frame*>& frames) {
  int next = 0;
  for (const Frame* f : frames) next = std::max(next, f->camera_id + 1);
  std::vector<Eigen::Matrix4d> poses;
  std::vector<int> numbers;
  for (const Frame* f : frames) {
    if (f->camera_id >= 0) {
      numbers.push_back(f->camera_id);
      continue;
    }
    std::size_t k = 0;
    while (k < poses.size() && poses[k] != f->camera.world_from_cam_gl) ++k;
    if (k == poses.size()) poses.push_back(f->camera.world_from_cam_gl);
    numbers.push_back(next + static_cast<int>(k));
  }
  return numbers;
}

}  // namespace

DatasetPipeline::DatasetPipeline(const CameraPipelineOptions& options,
                                 const std::string& crf_spec,
                                 const std::vector<const Frame*>& frames)
    : options_(options) {
  options_.Validate();
  if (options_.IsIdentity()) return;
  const std::vector<int> cameras = CameraNumbers(frames);
  double log_exposure_sum = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const Frame& f = *frames[i];
    log_exposure_sum += std::log(f.exposure);  // > 0: checked when the dataset was read
    if (!f.hdr_path) continue;
    if (view_of_hdr_.emplace(*f.hdr_path, views_.size()).second) {
      views_.push_back({.camera = cameras[i], .time = f.time});
      hdr_of_view_.push_back(*f.hdr_path);
    }
  }
  if (!frames.empty())
    reference_exposure_ = std::exp(log_exposure_sum / static_cast<double>(frames.size()));
  if (options_.NeedsStatistics()) {
    ParallelFor(static_cast<std::int64_t>(views_.size()), 1, [&](std::int64_t v) {
      const Image hdr = ReadHdrGroundTruth(hdr_of_view_[v]);
      views_[v].stats = MeasureFrame(hdr.Rgb(), options_.tone_low_percentile,
                                     options_.tone_high_percentile);
    });
  }
  processing_ = PlanViews(options_, views_, std::shared_ptr<const Crf>(ParseCrf(crf_spec)),
                          reference_exposure_);
}

Image DatasetPipeline::Synthesize(const Image& hdr, const Frame& frame, const Crf& base,
                                  const LdrSynthesisOptions& ldr) const {
  if (options_.IsIdentity()) return SynthesizeLdr(hdr, base, ldr);
  if (!frame.hdr_path || !view_of_hdr_.contains(*frame.hdr_path))
    Fail("camera pipeline: frame {} ({}) was not planned (no exr_file_path)", frame.index,
         frame.file_path);
  const std::size_t v = view_of_hdr_.at(*frame.hdr_path);
  return SynthesizeView(hdr, processing_[v], options_, base, ldr);
}

nlohmann::json DatasetPipeline::ToJson(const fs::path& root) const {
  nlohmann::json j = options_.ToJson();
  if (options_.name == "phone") j["reference_exposure"] = reference_exposure_;
  nlohmann::json views = nlohmann::json::array();
  for (std::size_t v = 0; v < views_.size(); ++v) {
    nlohmann::json view = {{"hdr", hdr_of_view_[v].lexically_relative(root).generic_string()},
                           {"camera", views_[v].camera},
                           {"time", views_[v].time}};
    if (options_.NeedsStatistics()) view["log_mean_luminance"] = views_[v].stats.log_mean;
    view.update(processing_[v].ToJson());
    views.push_back(std::move(view));
  }
  j["views"] = std::move(views);
  return j;
}

}  // namespace hdr4d
