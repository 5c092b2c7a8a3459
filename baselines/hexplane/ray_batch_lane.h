// The per-thread state of RayBatch (ray_batch.h), shared by its two source files.
#pragma once

#include <optional>
#include <vector>

#include "baselines/hexplane/ray_batch.h"

namespace hdr4d::baselines::hexplane {

// ln radiance is clamped before exp: e^30 (1e13) is far above any scene's radiance, and the
// clamp keeps a diverging MLP from overflowing float.
constexpr float kMaxLogRadiance = 30.0f;

struct RayBatch::Lane {
  int begin = 0, end = 0;           // rays [begin, end)
  std::vector<int> first, app_first;  // per ray (+1): first sample, first appearance row
  std::vector<float> xyz, feature, delta, alpha, weight, colour, transmittance;
  std::vector<int> app_sample;  // appearance row -> sample
  RowMatrix<float> products, feat, input, dout, din;
  std::vector<RowMatrix<float>> acts;
  std::optional<HexPlaneGrads> grads;

  void March(const HexPlaneModel& m, const Ray& ray, const float* jitter);
  void Appearance(const HexPlaneModel& m, const std::vector<Ray>& rays);
  void Backward(const HexPlaneModel& m, const std::vector<Ray>& rays, const float* dL_dout);
  void AppearanceBackward(const HexPlaneModel& m, const std::vector<Ray>& rays,
                          const std::vector<float>& dL_dcolour);
  // The ray of lane-local index i.
  const Ray& RayOf(const std::vector<Ray>& rays, int i) const { return rays[begin + i]; }
};

}  // namespace hdr4d::baselines::hexplane
