#include "method/render/view_renderer.h"

#include <algorithm>
#include <cmath>

#include "core/util/error.h"
#include "core/util/parallel.h"
#include "method/render/pixel_log.h"

namespace hdr4d::method {

ViewRenderer::ViewRenderer(const GaussianModel& model,
                           ToneMapper* tone_mapper,
                           const ResolvedHdrTraining& resolved,
                           const RenderOptions& base,
                           float background,
                           const std::vector<float>* learned_background,
                           const HdrHead* hdr_head)
    : model_(model), tone_mapper_(tone_mapper), resolved_(resolved), options_(base) {
  options_.background_source = nullptr;
  options_.backward_follows = false;  // outputs only: the blend keeps nothing for a backward
  if (learned_background) {
    learned_.emplace(*learned_background, resolved_.hdr_colors, tone_mapper);
    options_.background_source = &*learned_;
  }
  if (!resolved_.hdr_colors) {
    options_.color_stage = nullptr;
    options_.background.assign(model.channels, background);
    return;
  }
  // Tone-mapped Gaussians whenever the mapper can (even if training used only the HDR term).
  const bool map = tone_mapper && tone_mapper->pointwise() && !resolved_.final_ldr_from_pixels;
  stage_.emplace(tone_mapper, map);
  options_.color_stage = &*stage_;
  if (hdr_head && !hdr_head->empty()) {
    HDR4D_CHECK(hdr_head->offset.size() == model.size() * 3 && stage_->feature_channels() == 6);
    stage_->SetHdrOffset(hdr_head->offset.data(), nullptr);
    hdr_scale_ = std::exp(hdr_head->log_scale);
    if (!hdr_head->background.empty()) {
      HDR4D_CHECK(learned_.has_value() && hdr_head->background.size() == 3);  // ReadHdrHead
      learned_->SetHdrOffset(hdr_head->background.data(), nullptr);
    }
  }
  background_all_.assign(stage_->feature_channels(), 0.0f);
  for (int c = 3; c < stage_->feature_channels(); ++c) background_all_[c] = background;
  background_ldr_.assign(3, background);
}

void ViewRenderer::Render(const Camera& camera,
                          float time,
                          const ToneFrame& frame,
                          std::vector<float>* ldr,
                          std::vector<float>* hdr) {
  const std::size_t pixels =
      static_cast<std::size_t>(camera.intrinsics.width) * camera.intrinsics.height;
  if (!resolved_.hdr_colors) {
    raster_.resize(pixels * 3);
    RenderForward(model_, camera, time, options_, &state_, raster_.data());
    if (ldr) {
      ldr->resize(pixels * 3);
      std::transform(raster_.begin(), raster_.end(), ldr->begin(),
                     [](float v) { return std::clamp(v, 0.0f, 1.0f); });
    }
    if (hdr) hdr->clear();
    return;
  }
  stage_->SetFrame(frame, /*observe_bank=*/false);
  // No HDR image asked for and the LDR one is the tone-mapped Gaussians': only those 3 channels
  // are blended (the same LDR bits; docs/history/real-run-speed.md, twentieth pass).
  const bool ldr_only = !hdr && ldr && stage_->maps_gaussians();
  stage_->SetLdrOnly(ldr_only);
  if (learned_) learned_->SetLdrOnly(ldr_only);
  options_.background = ldr_only ? background_ldr_ : background_all_;
  const int channels = stage_->feature_channels();
  raster_.resize(pixels * channels);
  RenderForward(model_, camera, time, options_, &state_, raster_.data());
  if (ldr_only) {
    ldr->swap(raster_);  // the raster is the LDR image; the old buffer becomes the next raster
    for (float& v : *ldr) v = std::clamp(v, 0.0f, 1.0f);
    return;
  }
  // One parallel pass over the raster writes the HDR image (channels 0-2) and, when the raster
  // holds them, the tone-mapped Gaussians' LDR channels (3-5): two copies and two serial clamps
  // took about 1 ms of an 800x800 view's 30 with 2 threads.
  float* hdr_out = nullptr;
  float* ldr_out = nullptr;
  if (hdr) {
    hdr->resize(pixels * 3);
    hdr_out = hdr->data();
  }
  if (ldr && channels == 6) {
    ldr->resize(pixels * 3);
    ldr_out = ldr->data();
  }
  if (hdr_out || ldr_out) {
    const float* raster = raster_.data();
    const float scale = hdr_scale_;
    ParallelFor(static_cast<std::int64_t>(pixels), 16384, [&](std::int64_t p) {
      const float* px = raster + static_cast<std::size_t>(p) * channels;
      for (int c = 0; hdr_out && c < 3; ++c) hdr_out[3 * p + c] = std::max(px[c], 0.0f) * scale;
      for (int c = 0; ldr_out && c < 3; ++c) ldr_out[3 * p + c] = std::clamp(px[3 + c], 0.0f, 1.0f);
    });
  }
  if (!ldr || ldr_out) return;
  if (!tone_mapper_) {
    ldr->clear();  // HDR colours without a tone mapper (4dgs-hdr): no LDR output
    return;
  }
  // The 2D branch: the whole HDR image tone-mapped.
  ExtractChannels(raster_.data(), channels, 0, pixels, &x_);
  PixelLogImage(x_, resolved_.pixel_log_epsilon, &x_);
  ldr->resize(pixels * 3);
  tone_mapper_->MapImage(x_.data(), camera.intrinsics.width, camera.intrinsics.height, ldr->data());
  for (float& v : *ldr) v = std::clamp(v, 0.0f, 1.0f);
}

}  // namespace hdr4d::method
