// The static sigmoid tone mapper of HDR-HexPlane (Wu et al. 2024; ARCHITECTURE §4 "Baselines"):
// LDR_c = sigmoid(log_hdr_c + log exposure + delta_i) per channel, with no learned camera
// response and a learned log-exposure offset delta_i per training image i.
//
// Simplification: HDR-HexPlane computes the offset as MLP(Embedding[i]) (a scalar embedding, then
// Linear(1,64)-ReLU-Linear(64,1)). For a fixed image that is one scalar, and the network adds no
// expressiveness across images (any set of offsets is reachable by the embedding alone), so it
// is a reparameterisation of one learned scalar per image, which is what we learn directly
// (initialised at 0: the image's recorded exposure is trusted at first). A view that is no
// training image (image_index -1, e.g. a test view) uses the mean offset; its gradient, if it
// has a loss, spreads equally over every offset (the exact gradient of the mean). A common shift
// of all offsets can be absorbed by the radiance: the offsets are relative.
//
// Learning rate 0.01 (HDR-HexPlane's embedding uses 0.02 behind its MLP): Adam moves a parameter
// by about lr per step, and the sigmoid's slope is at most 1/4, so one step changes an LDR value
// by at most 0.0025, below one 8-bit code (0.0039); a one-stop correction (0.69) still takes only
// about 70 steps of that image, where the MLP rate (5e-4) would need about 1400.
#pragma once

#include <cstddef>

#include "baselines/param_tone_mapper.h"

namespace hdr4d::baselines {

// ldr (n x 3) = sigmoid(clamped log_hdr + log_exposure + offset).
template <typename T>
void SigmoidForward(T offset, T log_exposure, const T* log_hdr, std::size_t n, T* ldr);

// dL_dlog_hdr (n x 3, overwritten; may be null); dL/doffset is ADDED to *dL_doffset, reduced in
// chunk order (the same bits at any thread count).
template <typename T>
void SigmoidBackward(T offset,
                     T log_exposure,
                     const T* log_hdr,
                     std::size_t n,
                     const T* dL_dldr,
                     T* dL_dlog_hdr,
                     T* dL_doffset);

class SigmoidToneMapper final : public ParamToneMapper {
 public:
  static constexpr float kLearningRate = 0.01f;

  // One offset per config.num_images (none when it is 0: then a plain sigmoid).
  explicit SigmoidToneMapper(const method::ToneMapperConfig& config);

  bool pointwise() const override { return true; }
  // Also checks that the image index is -1 or below config().num_images.
  void BeginFrame(const method::ToneFrame& frame) override;
  void Map(const float* log_hdr, std::size_t n, float* ldr) const override;
  void MapBackward(const float* log_hdr,
                   std::size_t n,
                   const float* dL_dldr,
                   float* dL_dlog_hdr) override;
  float learning_rate() const override { return kLearningRate; }

  // The offset the current frame uses: its image's, or the mean for image_index -1.
  float FrameOffset() const;
};

}  // namespace hdr4d::baselines
