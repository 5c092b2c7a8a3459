#include "method/train/memory_check.h"

#include <algorithm>

#include "core/util/error.h"

namespace hdr4d::method {

namespace {
double GiB(std::uint64_t bytes) { return static_cast<double>(bytes) / (1024.0 * 1024.0 * 1024.0); }
}  // namespace

void CheckInitialCloudFits(const std::filesystem::path& ply,
                           std::int64_t points,
                           std::int64_t max_gaussians,
                           std::uint64_t available_bytes) {
  if (available_bytes == 0 || points <= 0) return;
  const std::int64_t start = max_gaussians > 0 ? std::min(points, max_gaussians) : points;
  const std::uint64_t need = static_cast<std::uint64_t>(start) * kTrainingBytesPerGaussian;
  if (need <= available_bytes) return;
  // Half of what is free: densification grows the cloud from there.
  const std::uint64_t fits = available_bytes / 2 / kTrainingBytesPerGaussian;
  Fail("{}: {} points would start training with {} Gaussians, which need at least {:.1f} GiB "
       "(about {:.1f} KB each for the model, its gradients and optimiser state), but only {:.1f} "
       "GiB are available to this process: pass --max-gaussians N with N around {} or less (the "
       "initial cloud is then subsampled to N points, evenly over the file), or thin the point "
       "cloud",
       ply.string(), points, start, GiB(need), kTrainingBytesPerGaussian / 1024.0,
       GiB(available_bytes), fits);
}

}  // namespace hdr4d::method
