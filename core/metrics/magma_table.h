// The 256-entry magma colour map (sRGB-encoded RGB in [0,1]); see magma_table.cpp.
#pragma once

#include <array>

namespace hdr4d {

const std::array<std::array<float, 3>, 256>& MagmaTable();

}  // namespace hdr4d
