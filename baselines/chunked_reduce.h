// The one way the baseline tone mappers accumulate parameter gradients over many values: each
// fixed chunk of the index range sums into its own partial, and the partials are added in chunk
// order. Chunk boundaries do not depend on the thread count, so neither do the bits of the sum.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/util/error.h"
#include "core/util/parallel.h"

namespace hdr4d::baselines {

// Calls fn(begin, end, partial) on the fixed chunks of [0, n) (at most `grain` long), possibly in
// parallel, each with its own zeroed array of `width` values; then ADDS the sum of the partials,
// formed in double in chunk order, to out[0 .. width).
template <typename T, typename Fn>
void ReduceInChunks(std::int64_t n, std::int64_t grain, std::size_t width, Fn&& fn, T* out) {
  HDR4D_CHECK(grain > 0);
  if (n <= 0) return;
  const std::int64_t chunks = (n + grain - 1) / grain;
  std::vector<T> partials(static_cast<std::size_t>(chunks) * width, T(0));
  ParallelForChunks(n, grain, [&](std::int64_t begin, std::int64_t end) {
    HDR4D_CHECK(begin % grain == 0 && end - begin <= grain);
    fn(begin, end, partials.data() + static_cast<std::size_t>(begin / grain) * width);
  });
  for (std::size_t k = 0; k < width; ++k) {
    double sum = 0.0;
    for (std::int64_t c = 0; c < chunks; ++c) sum += double(partials[std::size_t(c) * width + k]);
    out[k] += T(sum);
  }
}

}  // namespace hdr4d::baselines
