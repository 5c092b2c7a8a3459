// The order of a 4D model's Gaussians in memory. A frame of a dynamic scene shows only the
// Gaussians whose time window holds its time (70% are culled by time at the paper's Syn
// configuration), and every per-frame pass (colour rows, geometry, tile records, gradient rows)
// walks the model in index order. Densification appends its clones and children at the end, so
// after a few rounds a frame's Gaussians are scattered through hundreds of MB and each pass
// streams the culled rows between them. Sorted by the time their window opens, the Gaussians a
// frame keeps sit together (measured: docs/history/real-run-speed.md, issue 15's nineteenth pass).
//
// The trainer reorders a 4D model after initialisation and after every densification, both
// deterministic points of a run (a resumed run reorders where the uninterrupted one does).
// Adam's update is per element and the renderer's output does not depend on the order but for
// the rounding of sums and depth ties, so a reorder moves no parameter; the draws of the next
// densification (children in parent order) follow the new order.
#pragma once

#include <cstdint>
#include <vector>

#include "method/gaussian/gaussian_model.h"
#include "method/optim/adam.h"
#include "method/optim/densify.h"

namespace hdr4d::method {

// The order by the time each Gaussian's window opens: the first time at which its temporal
// marginal p(t) = exp(-(t - mu_t)^2 / 2 Sigma_tt) exceeds the renderer's cull threshold
// (kTemporalCullMarginal), mu_t - sqrt(2 ln(1 / threshold) Sigma_tt), clamped to
// [time_min, time_max]: a Gaussian open before the scene's first time (a static one) sorts with
// time_min. Ties keep the current order. Non-finite windows sort first. Entry k is the current
// index of the Gaussian that goes to row k.
std::vector<std::uint32_t> VisibleTimeOrder(const GaussianModel& model,
                                            float time_min,
                                            float time_max);

// Moves Gaussian order[k] to row k in every model buffer, in every model group of `adam` (when
// given and registered) and in `stats` (when given and of the model's size), in place: nothing
// is reallocated, so buffers bound elsewhere stay valid. `order` must be a permutation of the
// model's rows (checked).
void ReorderGaussians(const std::vector<std::uint32_t>& order,
                      GaussianModel* model,
                      Adam* adam,
                      DensifyStats* stats);

}  // namespace hdr4d::method
