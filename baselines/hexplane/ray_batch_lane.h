// The per-thread state of RayBatch (ray_batch.h), shared by its two source files.
#pragma once

#include <optional>
#include <vector>

#include "baselines/hexplane/ray_batch.h"

namespace hdr4d::baselines::hexplane {

// ln radiance is clamped before exp: e^30 (1e13) is far above any scene's radiance, and the
// clamp keeps a diverging MLP from overflowing float.
constexpr float kMaxLogRadiance = 30.0f;

// Training only: samples per ray that get a colour although their weight is under the threshold.
// The reference gives such samples no colour, so a pixel's gradient reaches their density only
// through the background (d pixel / d alpha_i = T_i (c_i - R_i) with c_i = 0): on its white
// backgrounds that starts the density, but on a black background (the D-NeRF copy in
// ../shared/data has its alpha dropped) c_i = R_i = 0 and an empty start never grows. A few
// coloured samples per ray, spread along it, restore the gradient (the pixel's value changes by
// their weights only, below the threshold each).
constexpr int kExploreSamples = 8;

struct RayBatch::Lane {
  int begin = 0, end = 0;           // rays [begin, end)
  std::vector<int> first, app_first;  // per ray (+1): first sample, first appearance row
  std::vector<float> xyz, feature, delta, alpha, weight, colour, transmittance;
  std::vector<float> background, background_pre;  // per ray: K channels, 3 pre-activations
  std::vector<int> app_sample;  // appearance row -> sample
  RowMatrix<float> products, feat, input, dout, din;
  std::vector<RowMatrix<float>> acts;
  std::optional<HexPlaneGrads> grads;

  void March(const HexPlaneModel& m, const Ray& ray, const float* jitter);
  // The background behind each ray of the lane (the fixed one, or background_env.h's).
  void Background(const HexPlaneModel& m, const std::vector<Ray>& rays);
  // Adds the learned background's gradients for the lane's rays, dL_dout of the whole batch.
  void BackgroundBackward(const HexPlaneModel& m, const std::vector<Ray>& rays,
                          const float* dL_dout);
  // explore > 0: that many more samples per ray below the weight threshold also get their
  // colour, spread evenly along the ray from `offset` (a fraction of the stride, in [0, 1)).
  void Appearance(const HexPlaneModel& m, const std::vector<Ray>& rays, int explore = 0,
                  float offset = 0.0f);
  // The colour of each appearance sample from the MLP's output (acts.back()): its LDR through the
  // tone mapper at the ray's exposure, and for log-HDR colours the radiance.
  void ToneMap(const HexPlaneModel& m, const std::vector<Ray>& rays);
  // The lane's rays composited over their background into out (K per ray of the whole batch).
  void CompositeRays(const HexPlaneModel& m, float* out) const;
  void Backward(const HexPlaneModel& m, const std::vector<Ray>& rays, const float* dL_dout);
  void AppearanceBackward(const HexPlaneModel& m, const std::vector<Ray>& rays,
                          const std::vector<float>& dL_dcolour);
  // The ray of lane-local index i.
  const Ray& RayOf(const std::vector<Ray>& rays, int i) const { return rays[begin + i]; }
};

}  // namespace hdr4d::baselines::hexplane
