// Rig mismatch: the cameras of a rig are not alike. Each camera but the reference (the
// smallest camera number) draws, from a generator keyed by (seed, camera) alone, so that a
// camera's draw does not depend on which others exist:
//   gain       g = exp(U(-G, G))
//   response   the dataset's bent to crf(x^e), e = 1 + U(-E, E)
//   colour     M = diag(exp(U(-C, C)) per channel) (I + D), D's off-diagonals U(-C, C) and its
//              diagonal minus their row sum, so (I + D) keeps grey grey and M tints it
// The reference camera has g = 1, e = 1, M = I.
#pragma once

#include <array>
#include <cstdint>

namespace hdr4d {

struct RigCameraDifference {
  double gain = 1;
  double exponent = 1;
  std::array<double, 9> colour = {1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major
};

RigCameraDifference DrawRigCamera(std::uint64_t seed, int camera, bool reference, double gain,
                                  double response, double colour);

}  // namespace hdr4d
