// Numeric constants of 4D Gaussian Splatting, in one place, with where they come from
// (ARCHITECTURE §4; 3DGS/4DGS reference rasteriser). Shared by the CPU kernels and any GPU port.
#pragma once

namespace hdr4d::method {

constexpr int kTileSize = 16;                   // pixels per tile side
constexpr float kTemporalCullMarginal = 0.05f;  // skip a Gaussian when p(t) <= this
constexpr float kCov2dDilation = 0.3f;      // added to the 2D covariance diagonal (anti-aliasing)
constexpr float kRadiusSigmas = 3.0f;       // screen radius = ceil(3 sqrt(lambda_max))
constexpr float kMaxAlpha = 0.99f;          // alpha = min(0.99, opacity p(t) G)
constexpr float kMinAlpha = 1.0f / 255.0f;  // contributions below this are skipped
constexpr float kMinTransmittance = 1e-4f;  // a pixel stops once T falls below this
constexpr float kNearPlane = 0.2f;          // Gaussians closer than this (camera z) are culled
constexpr float kFrustumTanMargin = 1.3f;   // 3DGS clamps t.x/t.z to 1.3 x tan(fov/2) in EWA
constexpr float kShC0 = 0.28209479177387814f;  // Y_00 = 1 / (2 sqrt(pi))
constexpr float kColorOffset = 0.5f;           // colour = SH value + 0.5

}  // namespace hdr4d::method
