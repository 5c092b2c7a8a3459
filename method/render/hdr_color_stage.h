// HDR-4DGS's 3D branch (ARCHITECTURE §4): each visible Gaussian's log-HDR colour c becomes the
// features the rasteriser blends, in one pass:
//   HDR only:            [exp(c)]                         (3 channels; 4dgs-hdr, or a mapper
//                                                          that needs whole images: Durand)
//   HDR + tone-mapped:   [exp(c), TM(c + log e)]          (6 channels; hdr4dgs, hdr-gs)
//   tone-mapped alone:   [TM(c + log e)]                  (3 channels; a render that asks for
//                                                          no HDR output: SetLdrOnly)
// Before mapping it writes the radiance bank (the mean log-HDR colour, ToneMapper::
// ObserveMeanLogHdr) and starts the tone mapper's frame (BeginFrame), so the context learner of
// the Dynamic Tone Mapper sees the row written for this very frame when it is the first one.
//
// The bank's mean runs over the Gaussians present at the frame's time (not culled by the
// temporal marginal or the frustum), not over every Gaussian as the reference does: a culled
// Gaussian then costs nothing, and the mean describes what the frame shows. Said in README.
//
// With an HDR head (hdr_head.h) the HDR channels are exp(c + d) for the Gaussian's
// log-radiance offset d, and the tone-mapped channels stay TM(c + log e): the head changes the
// HDR output and nothing the LDR output shows.
//
// exp is evaluated at min(c, kMaxLogRadiance) (radiance up to e^30 ~ 1e13) so no blended value
// can overflow; beyond it the gradient is 0.
#pragma once

#include <cstdint>
#include <vector>

#include "method/render/frame_state.h"
#include "method/tonemap/tone_mapper.h"

namespace hdr4d::method {

inline constexpr float kMaxLogRadiance = 30.0f;

// exp(min(c, kMaxLogRadiance)) and its derivative, in any floating type.
template <typename T>
inline T GuardedExp(T c) {
  return c < T(kMaxLogRadiance) ? std::exp(c) : std::exp(T(kMaxLogRadiance));
}
template <typename T>
inline T GuardedExpBackward(T c, T dL_dy) {
  return c < T(kMaxLogRadiance) ? dL_dy * std::exp(c) : T(0);
}

class HdrColorStage final : public ColorStage {
 public:
  // tone_mapper may be null (HDR only). With map_gaussians false (or a mapper that is not
  // pointwise) the stage still writes the bank and begins the frame, but blends HDR only.
  HdrColorStage(ToneMapper* tone_mapper, bool map_gaussians);

  // The view the next Forward renders. observe_bank: write the radiance bank (every render does,
  // as in the reference; off for renders that must not change the run, e.g. tone-curve plots).
  void SetFrame(const ToneFrame& frame, bool observe_bank) {
    frame_ = frame;
    observe_bank_ = observe_bank;
  }
  bool maps_gaussians() const { return map_; }
  // The HDR head's offsets (N x 3 in the model's order; null: none) and, for fitting it, where
  // Backward writes dL/d(offset) of the visible Gaussians (null: not written).
  void SetHdrOffset(const float* offset, float* offset_grad) {
    offset_ = offset;
    offset_grad_ = offset_grad;
  }

  // A render that asks for the tone-mapped image alone (no HDR output) blends [TM(c + log e)]:
  // 3 channels instead of 6, holding the same values as channels 3-5 would, so the LDR image is
  // the same bit for bit at about half the blend's per-channel work. For renders only (Backward
  // refuses), and only when the stage maps Gaussians (checked).
  void SetLdrOnly(bool ldr_only);

  int feature_channels() const override { return map_ && !ldr_only_ ? 6 : 3; }
  void Forward(const float* colors,
               int color_channels,
               const std::vector<std::uint32_t>& visible,
               float* features) override;
  void Backward(const float* colors,
                int color_channels,
                const std::vector<std::uint32_t>& visible,
                const float* dL_dfeatures,
                float* dL_dcolors) override;

 private:
  ToneMapper* tm_;
  bool map_;
  ToneFrame frame_;
  bool observe_bank_ = true;
  bool ldr_only_ = false;
  const float* offset_ = nullptr;
  float* offset_grad_ = nullptr;
  std::vector<float> packed_, ldr_, dldr_, dlog_;  // compact rows of the visible Gaussians
};

}  // namespace hdr4d::method
