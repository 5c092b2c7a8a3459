// Reordering the rows of a buffer in place (the model's and the optimiser's per-Gaussian
// buffers, time_order.h): cycle by cycle through one row of scratch, so that hundreds of MB of
// parameters and moments are reordered without a second copy of any of them.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace hdr4d::method {

namespace permute_detail {

// Rows of W floats (W = 0: `width`, known only at run time). A cycle is a chain of dependent
// random reads, so the rows a few steps ahead on it are prefetched.
template <std::size_t W>
void PermuteRows(float* data, std::size_t width, std::span<const std::uint32_t> order) {
  if constexpr (W > 0) width = W;
  const std::size_t n = order.size();
  constexpr int kAhead = 8;
  std::vector<char> placed(n, 0);
  std::vector<float> first(width);
  const auto move = [&](std::size_t to, const float* from) {
    if constexpr (W > 0) {
      for (std::size_t c = 0; c < W; ++c) data[to * W + c] = from[c];
    } else {
      std::copy_n(from, width, data + to * width);
    }
  };
  for (std::size_t start = 0; start < n; ++start) {
    if (placed[start] || order[start] == start) continue;
    // Follow the cycle start <- order[start] <- order[order[start]] ... back to start.
    std::copy_n(data + start * width, width, first.begin());
    std::size_t at = start, ahead = start;
    for (int k = 0; k < kAhead; ++k) ahead = order[ahead];
    for (;;) {
      placed[at] = 1;
      const std::size_t from = order[at];
      if (from == start) {
        move(at, first.data());
        break;
      }
      const char* line = reinterpret_cast<const char*>(data + ahead * width);
      for (std::size_t b = 0; b < width * sizeof(float); b += 64) __builtin_prefetch(line + b);
      ahead = order[ahead];
      move(at, data + from * width);
      at = from;
    }
  }
}

}  // namespace permute_detail

// New row k of `data` (rows of `width` floats) becomes old row order[k]. `order` must be a
// permutation of 0..rows-1 (the caller checks: IsPermutation).
inline void PermuteRowsInPlace(float* data,
                               std::size_t width,
                               std::span<const std::uint32_t> order) {
  if (width == 0 || order.empty()) return;
  switch (width) {
    case 1:
      return permute_detail::PermuteRows<1>(data, width, order);
    case 3:
      return permute_detail::PermuteRows<3>(data, width, order);
    case 4:
      return permute_detail::PermuteRows<4>(data, width, order);
    default:
      return permute_detail::PermuteRows<0>(data, width, order);
  }
}

// True when `order` holds each of 0..order.size()-1 exactly once.
inline bool IsPermutation(std::span<const std::uint32_t> order) {
  std::vector<char> seen(order.size(), 0);
  for (const std::uint32_t k : order) {
    if (k >= order.size() || seen[k]) return false;
    seen[k] = 1;
  }
  return true;
}

}  // namespace hdr4d::method
