// Third-party and standard headers most of hdr4d's libraries include, precompiled once and
// reused by every library (cmake/Hdr4dHelpers.cmake, HDR4D_PCH). Never hdr4d's own headers: a
// change to one of them must not rebuild this.
#pragma once

#include <fmt/format.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>
