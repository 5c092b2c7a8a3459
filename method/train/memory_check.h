// Whether a new run's initial Gaussians fit in memory, checked from the point cloud's header
// before anything is read or written (issue 51 §12: a 10-million-point point3d.ply on a 32x32
// scene grew train to 24 GB and was OOM-killed, leaving its run folder behind).
#pragma once

#include <cstdint>
#include <filesystem>

namespace hdr4d::method {

// At least this much memory per Gaussian while training: the model, its gradients, the
// optimiser's two moments and the densification statistics (the model of HDR-4DGS alone is
// ~0.7 KB; the run's measured growth on the cloud was ~2.4 KB per point).
inline constexpr std::uint64_t kTrainingBytesPerGaussian = 2304;

// Throws hdr4d::Error naming `ply` when `points` initial Gaussians (after `max_gaussians`, 0 = no
// cap, has subsampled the cloud) would need more than `available_bytes`, saying how much they
// need and what to do (--max-gaussians N, which subsamples the cloud). available_bytes 0:
// unknown, nothing is checked.
void CheckInitialCloudFits(const std::filesystem::path& ply,
                           std::int64_t points,
                           std::int64_t max_gaussians,
                           std::uint64_t available_bytes);

}  // namespace hdr4d::method
