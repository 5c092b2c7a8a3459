// The 2D (pixel) branch's input (ARCHITECTURE §4): the HDR channels of the raster as
// log(max(HDR, 0) + eps), which the tone mapper maps per pixel. Forward and derivative side by
// side; the training loss (method/train/hdr_loss.h) runs the backward, the renderers of a
// finished run (view_renderer.h) the forward.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

namespace hdr4d::method {

// The floor eps of the 2D branch's log(HDR + eps). The reference's 1e-5 is harmless under LDR
// supervision alone, where the model picks its own radiance scale. An HDR term fixes the raster to
// the target's units (each image, or the scene, over its maximum), where the darkest radiance an
// LDR bracket still records sits near 1e-5 on a scene of 1e5:1 (two exposures 256x apart record
// 1/65000 of the top): the 2D branch then cannot tell those pixels from black and fights the HDR
// term there (issue 12 §3, docs/history/accuracy.md: 2.4 dB of held-out LDR on studio). So with an
// HDR term the floor is 1e-8 of the target's maximum (ResolveHdrTraining,
// method/train/hdr_training_options.h).
inline constexpr float kReferencePixelLogEpsilon = 1e-5f;
inline constexpr float kHdrUnitsPixelLogEpsilon = 1e-8f;

// log(max(HDR, 0) + eps), and its derivative.
template <typename T>
inline T PixelLog(T hdr, T eps) {
  return std::log((hdr > T(0) ? hdr : T(0)) + eps);
}
template <typename T>
inline T PixelLogBackward(T hdr, T dL_dy, T eps) {
  return hdr > T(0) ? dL_dy / (hdr + eps) : T(0);
}

// Channels [first, first + 3) of an interleaved H x W x channels buffer as a 3-channel one.
void ExtractChannels(
    const float* src, int channels, int first, std::size_t pixels, std::vector<float>* dst);
// The 2D branch's input for every value of a 3-channel HDR image: PixelLog of each.
void PixelLogImage(const std::vector<float>& hdr, float eps, std::vector<float>* x);

}  // namespace hdr4d::method
