// Initial 4D Gaussians (ARCHITECTURE §4, reference create_from_pcd): from the scene's point cloud or
// uniformly at random in a cube, isotropic scales from the distance to the 3 nearest
// neighbours, identity rotations, opacity 0.1, times from the cloud or uniform over a slightly
// widened time span, temporal scale sqrt(T/5).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "core/geometry/ply.h"
#include "method/gaussian/gaussian_model.h"

namespace hdr4d::method {

struct InitOptions {
  int num_random_points = 50000;    // HDR-4D-Syn configs use 50k (5 scenes) or 100k (3 scenes)
  float random_half_extent = 1.3f;  // random points uniform in [-1.3, 1.3]^3
  float time_min = -0.1f;           // random times uniform in [time_min, time_max]
  float time_max = 1.1f;
  float time_duration = 1.0f;  // T: Sigma_tt = T / 5 at start
  float initial_opacity = 0.1f;
  std::uint64_t seed = 0;
  bool temporal = true;
  ColorMode color_mode = ColorMode::kLdr;
  ColorBasis basis;
  int channels = 3;
  void Validate() const;
};

// Mean squared distance of each point to its 3 nearest neighbours (exact, through a k-d tree;
// the reference uses simple-knn on the GPU). Floored at 1e-7 as the reference does.
std::vector<float> MeanSquaredDistanceToThreeNearest(const std::vector<Eigen::Vector3f>& points);

// --max-gaussians caps the initial cloud too: a cloud of N > max_points points keeps
// max_points of them, evenly spread over the file's order (point floor(k N / max_points) for
// k = 0, 1, ...), colours and times with them. Deterministic; a smaller cloud is kept whole.
void SubsamplePointCloud(PointCloud* cloud, std::size_t max_points);

// Points from `cloud` when given (colours and times used when present), else random ones.
// A cloud whose points all carry t = 0 (datagen before issue 56) keeps t = 0: that is when its
// points were sampled. Drawing its times uniformly instead, as for a cloud without times, lost
// held-out LDR PSNR (deer -0.16 dB, tank -0.25 dB, 2000 iterations; BENCHMARKS.md), while a
// cloud sampled over time (datagen now) gained (+0.59, +0.22 dB).
GaussianModel InitialiseGaussians(const std::optional<PointCloud>& cloud,
                                  const InitOptions& options);

// Under an HDR term the raster is in the HDR target's units, which the points' LDR colours know
// nothing of: with image-max targets the median pixel of a scene with a bright lamp is 1e-4 of
// its image's maximum, so colours started at the points' values made the first renders ~10^3x
// too bright, and the HDR term's first hundreds of steps went into opacity (which moves fast)
// rather than the log colours (which move slowly), pruning the geometry
// (docs/history/accuracy.md, "The cause of LDR+HDR's deficit"). Adds one constant to every
// log-HDR DC colour so that their median is `log_level`; returns the constant (log units).
float ShiftLogColoursToLevel(GaussianModel* model, float log_level);

}  // namespace hdr4d::method
