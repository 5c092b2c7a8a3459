#include "method/optim/time_order.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/util/error.h"
#include "core/util/parallel.h"
#include "method/gaussian/constants.h"
#include "method/gaussian/rotation4d.h"
#include "method/gaussian/slice.h"
#include "method/optim/permute_rows.h"

namespace hdr4d::method {

std::vector<std::uint32_t> VisibleTimeOrder(const GaussianModel& model,
                                            float time_min,
                                            float time_max) {
  HDR4D_CHECK(time_min <= time_max);
  const std::size_t n = model.size();
  // dt^2 >= cut Sigma_tt <=> p(t) <= the threshold (the renderer's test).
  const double cut = 2.0 * std::log(1.0 / static_cast<double>(kTemporalCullMarginal));
  std::vector<std::pair<float, std::uint32_t>> keyed(n);
  ParallelFor(static_cast<std::int64_t>(n), 4096, [&](std::int64_t g) {
    const auto i = static_cast<std::size_t>(g);
    Vec4<double> ql, qr, log_scales;
    for (int k = 0; k < 4; ++k) {
      ql(k) = model.rot_left[4 * i + k];
      qr(k) = model.rot_right[4 * i + k];
      log_scales(k) = model.log_scales[4 * i + k];
    }
    bool floored = false;
    const double stt =
        detail::SliceTimeVariance(Covariance4D(Rotation4D(ql, qr), log_scales), &floored);
    const double opens = static_cast<double>(model.t[i]) - std::sqrt(cut * stt);
    // NaN compares false both ways: such a window sorts with the first.
    const float key =
        opens > time_min ? static_cast<float>(std::min<double>(opens, time_max)) : time_min;
    keyed[i] = {key, static_cast<std::uint32_t>(i)};
  });
  // (key, index) pairs are distinct, so an unstable sort keeps ties in the current order.
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> order(n);
  for (std::size_t k = 0; k < n; ++k) order[k] = keyed[k].second;
  return order;
}

void ReorderGaussians(const std::vector<std::uint32_t>& order,
                      GaussianModel* model,
                      Adam* adam,
                      DensifyStats* stats) {
  HDR4D_CHECK(model != nullptr && order.size() == model->size() && IsPermutation(order));
  // Every buffer is reordered on its own: one job each, spread over the threads.
  std::vector<std::pair<float*, std::size_t>> buffers;
  const auto groups = ModelGroupBuffers(*model);
  for (std::size_t k = 0; k < groups.size(); ++k) {
    const std::size_t width = GroupRowWidth(*model, kModelGroups[k]);
    if (width > 0) buffers.emplace_back(groups[k]->data(), width);
  }
  if (stats != nullptr && stats->size() == order.size()) {
    for (std::vector<float>* v :
         {&stats->grad_accum, &stats->denom, &stats->max_radii, &stats->max_weight}) {
      if (!v->empty()) buffers.emplace_back(v->data(), 1);  // max_weight: only when tracked
    }
  }
  std::vector<const char*> moments;  // the Adam groups, reordered through Adam (one job each)
  if (adam != nullptr) {
    for (const char* name : kModelGroups) {
      if (adam->HasGroup(name) && GroupRowWidth(*model, name) > 0) moments.push_back(name);
    }
  }
  const auto jobs = static_cast<std::int64_t>(buffers.size() + moments.size());
  ParallelFor(jobs, 1, [&](std::int64_t j) {
    const auto k = static_cast<std::size_t>(j);
    if (k < buffers.size()) {
      PermuteRowsInPlace(buffers[k].first, buffers[k].second, order);
    } else {
      const char* name = moments[k - buffers.size()];
      adam->PermuteRows(name, order, GroupRowWidth(*model, name));
    }
  });
}

}  // namespace hdr4d::method
