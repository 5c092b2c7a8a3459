// One view of a trained model as its outputs: the final LDR image and, for HDR colours, the HDR
// image (ARCHITECTURE §4: the final LDR render is the 3D branch, or the 2D branch for a whole-image
// tone mapper; the final HDR render is the HDR raster). Shared by the trainer's evaluation and
// `hdr4d render`. Rendering here never writes the radiance bank: looking at a run does not
// change it.
#pragma once

#include <optional>
#include <vector>

#include "core/geometry/camera.h"
#include "method/render/frame_render.h"
#include "method/render/hdr_color_stage.h"
#include "method/render/hdr_head.h"
#include "method/render/learned_background.h"
#include "method/render/resolved_hdr_training.h"

namespace hdr4d::method {

class ViewRenderer {
 public:
  // The model and tone mapper (may be null) must outlive the renderer. `base` gives the colour
  // degrees, time span, backend and the LDR background (one value, repeated). learned_background:
  // the run's learned background (learned_background.h) when it has one; it replaces the grey.
  // hdr_head: the run's HDR head (hdr_head.h; null or empty: none), which must outlive it; it
  // changes the HDR output only, which needs the LDR from the tone-mapped Gaussians.
  ViewRenderer(const GaussianModel& model,
               ToneMapper* tone_mapper,
               const ResolvedHdrTraining& resolved,
               const RenderOptions& base,
               float background,
               const std::vector<float>* learned_background = nullptr,
               const HdrHead* hdr_head = nullptr);

  // ldr: H x W x 3 in [0,1]; hdr: H x W x 3 linear radiance (left empty for an LDR model).
  // Either may be null; with hdr null the HDR channels are not blended at all when the LDR image
  // is the tone-mapped Gaussians' (the LDR image is the same either way).
  void Render(const Camera& camera,
              float time,
              const ToneFrame& frame,
              std::vector<float>* ldr,
              std::vector<float>* hdr);

  bool has_hdr() const { return resolved_.hdr_colors; }
  bool has_ldr() const { return !resolved_.hdr_colors || tone_mapper_ != nullptr; }

 private:
  const GaussianModel& model_;
  ToneMapper* tone_mapper_;
  ResolvedHdrTraining resolved_;
  RenderOptions options_;
  std::optional<HdrColorStage> stage_;
  std::optional<LearnedBackground> learned_;
  FrameState state_;
  std::vector<float> raster_, x_;
  // The LDR background of the blend's channels: [0, 0, 0, b, b, b] (or the HDR-only zeros), and
  // [b, b, b] when only the tone-mapped channels are blended.
  std::vector<float> background_all_, background_ldr_;
  float hdr_scale_ = 1.0f;  // the HDR head's factor
};

}  // namespace hdr4d::method
