// --iterations auto (issue 55): whether a run's training loss has stopped improving. Decided
// from the loss of every iteration so far alone (RUN/checkpoint.bin keeps that curve), so a run
// stops at the same iteration whether or not it was interrupted and resumed.
#pragma once

#include <optional>
#include <vector>

namespace hdr4d::method {

struct LossPlateau {
  int iteration = 0;      // the iteration after which the run stops
  double previous = 0;    // mean loss of iterations (iteration - 2 window, iteration - window]
  double last = 0;        // mean loss of iterations (iteration - window, iteration]
  double improvement = 0; // (previous - last) / previous
};

// With loss_curve[i] the loss of iteration i + 1: a plateau when the curve's length is a
// multiple of `window` (> 0), both windows lie after `densify_until` (the model no longer
// grows, no opacity reset lifts the loss) and the last window's mean improved on the one before
// by less than `tolerance` of it. nullopt otherwise (window 0: never).
std::optional<LossPlateau> FindLossPlateau(const std::vector<double>& loss_curve,
                                           int densify_until,
                                           int window,
                                           double tolerance);

}  // namespace hdr4d::method
