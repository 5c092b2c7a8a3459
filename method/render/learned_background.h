// A background learned with the scene (`hdr4d train --learn-background`; not in the paper, whose
// reference trains on a fixed black background): one colour behind every Gaussian, the same in
// every view and at every time. Why: a uniform sky or backdrop on a fixed background has to be
// built from Gaussians, and with few, widely spaced cameras nothing fixes their depth, so they
// float in front of the scene from a held-out camera (docs/history/accuracy.md). One
// learned value per channel explains such a backdrop at infinity instead.
//
// For log-HDR colours the value b is a log radiance, blended the way a Gaussian's colour is
// (hdr_color_stage.h): [exp(b)] on 3 channels, or [exp(b), TM(b + log e)] on 6, through the tone
// mapper's frame that the colour stage began. The 2D branch then maps the blended HDR, backdrop
// included, like any pixel. For LDR colours b is the blended colour itself, not clamped (the loss
// keeps it where the images put it; the rendered LDR image is clamped to [0, 1] as always).
//
// Backward: dL/db = exp(b) dL/dbg_hdr + TM'(b + log e) dL/dbg_ldr, or dL/dbg for LDR colours;
// added to grads(). The backdrop does not train the tone curve: TM' is the mapper's slope at b
// (central differences of Map, step 1e-3 in log radiance; exact within a tabulated curve's
// segment, O(step^2) elsewhere), and the curve's parameters get no gradient from the backdrop.
// With the curve's gradient, the backdrop's many pixels bent the curve's dark end towards a
// value no Gaussian has: on studio (a black backdrop) held-out LDR fell 0.24 dB below the fixed
// background and the HDR's log correlation from 0.90 to 0.85; without it, -0.07 dB
// (docs/history/accuracy.md, "A learned background"). The 2D branch still maps the blended HDR,
// backdrop included, through the curve with its full gradient, as it maps a fixed background's
// pixels.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "method/render/frame_state.h"
#include "method/tonemap/tone_mapper.h"

namespace hdr4d::method {

// The key of a checkpoint's trainer state that holds the values.
inline constexpr const char* kLearnedBackgroundKey = "learned_background";

// Values a model's learned background has: 3 (a log radiance) for log-HDR colours, else one per
// colour channel.
int LearnedBackgroundChannels(const GaussianModel& model);

// The values saved under kLearnedBackgroundKey in `trainer` (a checkpoint's trainer state).
// Throws hdr4d::Error naming `source` when they are missing, not `channels` many, or not finite.
std::vector<float> ReadLearnedBackground(const nlohmann::json& trainer, int channels,
                                         const std::string& source);

class LearnedBackground final : public BackgroundSource {
 public:
  // values: 3 for log-HDR colours, else one per model channel. tone_mapper may be null (HDR only,
  // or LDR colours); it must map pointwise when a 6-channel background is asked for.
  LearnedBackground(std::vector<float> values, bool log_hdr, ToneMapper* tone_mapper);

  void Forward(int channels, std::vector<float>* background) override;
  void Backward(int channels, const float* dL_dbackground) override;

  // The HDR head's offset (hdr_head.h): the HDR channels show exp(b + offset), the
  // tone-mapped ones keep TM(b + log e). offset_grad (may be null) gets dL/d(offset), added, as b
  // does. Both arrays hold 3 values and must outlive their use; null: no offset.
  void SetHdrOffset(const float* offset, float* offset_grad) {
    offset_ = offset;
    offset_grad_ = offset_grad;
  }

  // With the colour stage's tone-mapped-alone render (HdrColorStage::SetLdrOnly): 3 channels
  // of TM(b + log e), the values channels 3-5 would hold. Forward only (Backward refuses).
  void SetLdrOnly(bool ldr_only) { ldr_only_ = ldr_only; }

  std::vector<float>& params() { return values_; }
  const std::vector<float>& params() const { return values_; }
  std::vector<float>& grads() { return grads_; }
  void ZeroGrad();

 private:
  std::vector<float> values_, grads_;
  bool log_hdr_;
  ToneMapper* tm_;
  const float* offset_ = nullptr;
  float* offset_grad_ = nullptr;
  bool ldr_only_ = false;
};

}  // namespace hdr4d::method
