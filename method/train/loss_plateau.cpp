#include "method/train/loss_plateau.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace hdr4d::method {

std::optional<LossPlateau> FindLossPlateau(const std::vector<double>& loss_curve,
                                           int densify_until,
                                           int window,
                                           double tolerance) {
  if (window <= 0) return std::nullopt;
  const std::size_t n = loss_curve.size();
  const auto w = static_cast<std::size_t>(window);
  if (n % w != 0 || n < 2 * w) return std::nullopt;
  if (static_cast<long long>(n) - 2 * static_cast<long long>(w) < std::max(densify_until, 0))
    return std::nullopt;
  double previous = 0, last = 0;
  for (std::size_t i = n - 2 * w; i < n - w; ++i) previous += loss_curve[i];
  for (std::size_t i = n - w; i < n; ++i) last += loss_curve[i];
  previous /= static_cast<double>(w);
  last /= static_cast<double>(w);
  // A loss at (or below) zero has nothing left to improve; the division is guarded.
  const double improvement = previous > 1e-300 ? (previous - last) / previous : 0.0;
  if (!(improvement < tolerance)) return std::nullopt;
  return LossPlateau{static_cast<int>(n), previous, last, improvement};
}

namespace {

// PSNR to mean squared error; a non-finite PSNR (a view that could not be scored) never counts
// as an improvement.
double HeldOutError(double psnr) {
  return std::isfinite(psnr) ? std::pow(10.0, -psnr / 10.0) : HUGE_VAL;
}

// Whether `point` lowered the val error below (1 - tolerance) x `best`'s: the one gain rule of
// the stop and the growth stop.
bool Improves(const HeldOutPoint& point, const HeldOutPoint& best, double tolerance) {
  return HeldOutError(point.psnr) < (1.0 - tolerance) * HeldOutError(best.psnr);
}

}  // namespace

std::optional<std::size_t> BestHeldOutIndex(const std::vector<HeldOutPoint>& curve,
                                            double tolerance) {
  if (curve.empty()) return std::nullopt;
  std::size_t best = 0;
  for (std::size_t i = 1; i < curve.size(); ++i) {
    if (Improves(curve[i], curve[best], tolerance)) best = i;
  }
  return best;
}

std::optional<HeldOutPlateau> FindHeldOutPlateau(const std::vector<HeldOutPoint>& curve,
                                                 double tolerance,
                                                 int patience) {
  if (patience < 1 || curve.size() < static_cast<std::size_t>(patience) + 1) return std::nullopt;
  const std::size_t best = *BestHeldOutIndex(curve, tolerance);
  if (curve.size() - 1 - best < static_cast<std::size_t>(patience)) return std::nullopt;
  return HeldOutPlateau{curve.back().iteration, curve[best].iteration, curve[best].psnr,
                        curve.back().psnr};
}

std::optional<GrowthStop> FindGrowthStop(const std::vector<HeldOutPoint>& curve,
                                         int densify_until,
                                         double tolerance) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < curve.size() && curve[i].iteration < densify_until; ++i) {
    if (Improves(curve[i], curve[best], tolerance)) {
      best = i;
    } else if (curve[i].gaussians > 0) {
      return GrowthStop{curve[i].iteration, curve[i].gaussians};
    }
  }
  return std::nullopt;
}

}  // namespace hdr4d::method
