// The per-value loop of the tabulated tone curves in float SIMD (Highway, every x86 target,
// chosen at run time): locate x in the table, gather the two nodes, interpolate, sigmoid; the
// backward also gives dL/dx and each value's two node gradients, which the caller scatters
// (DtmCore). Same maths as DtmCore's scalar loop (which the double tests check against finite
// differences); only the exp differs in the last bits.
#pragma once

#include <cstddef>
#include <cstdint>

namespace hdr4d::method::detail {

// The three channels' tables of one frame, concatenated: channel c's node j at c * nodes + j;
// dz[c * nodes + j] = z[c * nodes + j + 1] - z[c * nodes + j] (0 for a channel's last node).
struct ToneTableView {
  const float* z = nullptr;
  const float* dz = nullptr;
  int nodes = 0;
  float x_min = 0, x_max = 0, inv_step = 0, log_exposure = 0;
};

// Over `count` interleaved RGB values (a multiple of 3, the first one red): ldr for every value
// whose x = log_hdr + log_exposure lies in [x_min, x_max]; the positions of the others (outside
// or NaN) go to `outside`, and the count of those is returned: the caller maps them directly.
std::size_t ToneTableForward(const ToneTableView& table,
                             const float* log_hdr,
                             std::size_t count,
                             float* ldr,
                             std::int32_t* outside);

// Backward of ToneTableForward: for values inside, dL/dx (dz * slope), the index of the
// interval's first node in the concatenated table, and the node gradients a0 = dz (1 - w),
// a1 = dz w (0 and 0 for values outside); positions of values outside as in the forward.
std::size_t ToneTableBackward(const ToneTableView& table,
                              const float* log_hdr,
                              const float* dL_dldr,
                              std::size_t count,
                              float* dL_dlog_hdr,
                              std::int32_t* node,
                              float* a0,
                              float* a1,
                              std::int32_t* outside);

}  // namespace hdr4d::method::detail
