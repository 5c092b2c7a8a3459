// --iterations auto (issue 55): whether a run's training loss has stopped improving. Decided
// from the loss of every iteration so far alone (RUN/checkpoint.bin keeps that curve), so a run
// stops at the same iteration whether or not it was interrupted and resumed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace hdr4d::method {

struct LossPlateau {
  int iteration = 0;       // the iteration after which the run stops
  double previous = 0;     // mean loss of iterations (iteration - 2 window, iteration - window]
  double last = 0;         // mean loss of iterations (iteration - window, iteration]
  double improvement = 0;  // (previous - last) / previous
};

// With loss_curve[i] the loss of iteration i + 1: a plateau when the curve's length is a
// multiple of `window` (> 0), both windows lie after `densify_until` (the model no longer
// grows, no opacity reset lifts the loss) and the last window's mean improved on the one before
// by less than `tolerance` of it. nullopt otherwise (window 0: never).
std::optional<LossPlateau> FindLossPlateau(const std::vector<double>& loss_curve,
                                           int densify_until,
                                           int window,
                                           double tolerance);

// --stop-on-val: the held-out signal. One point per evaluation of the scene's val split.
struct HeldOutPoint {
  int iteration = 0;
  double psnr = 0;  // mean LDR PSNR over the val views (dB)
  std::int64_t gaussians = 0;  // the model's count when scored (0: not recorded)
};

struct HeldOutPlateau {
  int iteration = 0;       // the iteration after which the run stops (the last evaluation)
  int best_iteration = 0;  // the evaluation that last improved the best
  double best_psnr = 0;
  double last_psnr = 0;
};

// Evaluations of the val split a run waits for an improvement before it stops.
inline constexpr int kHeldOutPatience = 3;

// The best evaluation so far: the last one that lowered the val split's mean squared error
// (10^(-PSNR/10)) below (1 - tolerance) x the best before it (the first point starts the best).
// Its index in `curve`; nullopt for an empty curve.
std::optional<std::size_t> BestHeldOutIndex(const std::vector<HeldOutPoint>& curve,
                                            double tolerance);

// A plateau when none of the last `patience` evaluations improved on the best (the rule above):
// the relative gain of the training-loss rule, on held-out views. Unlike the training loss, the
// held-out error can rise while the training loss still falls (a model that overfits its
// views); the rule stops there, `patience` evaluations after the best, on the last model (with
// --keep-best-val the trainer takes back the best evaluation's). nullopt with fewer than
// patience + 1 points.
std::optional<HeldOutPlateau> FindHeldOutPlateau(const std::vector<HeldOutPoint>& curve,
                                                 double tolerance,
                                                 int patience = kHeldOutPatience);

// --grow-on-val: the first evaluation before `densify_until` (the model still grows) that did not
// lower the val error below (1 - tolerance) x the best before it, by the rule above; nullopt
// while every one did, or where no count was recorded. From then on densification keeps the
// count at or under that evaluation's: what the model added since its best did not pay on the
// held-out views, and more of it costs every later iteration (a budget set by the scene, where
// a fixed factor of the image size is too many on one scene and too few on another).
struct GrowthStop {
  int iteration = 0;
  std::int64_t gaussians = 0;
};
std::optional<GrowthStop> FindGrowthStop(const std::vector<HeldOutPoint>& curve,
                                         int densify_until,
                                         double tolerance);

}  // namespace hdr4d::method
