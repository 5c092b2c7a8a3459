#include "method/gaussian_model.h"

#include <fmt/format.h>

namespace hdr4d::method {

void GaussianModel::Resize(std::size_t n) {
  const std::size_t old = size();
  means.resize(n * 4, 0.0f);
  log_scales.resize(n * 4, 0.0f);
  rot_left.resize(n * 4, 0.0f);
  rot_right.resize(n * 4, 0.0f);
  opacity_logit.resize(n, 0.0f);
  color.resize(n * basis.coefficients() * channels, 0.0f);
  for (std::size_t i = old; i < n; ++i) rot_left[i * 4] = rot_right[i * 4] = 1.0f;  // identity
}

std::string GaussianModel::Validate() const {
  const std::size_t n = size();
  const std::size_t k = static_cast<std::size_t>(basis.coefficients()) * channels;
  if (means.size() != n * 4 || log_scales.size() != n * 4 || rot_left.size() != n * 4 ||
      rot_right.size() != n * 4 || color.size() != n * k) {
    return fmt::format("Gaussian buffers disagree: {} opacities, {} means/4, {} colours/{}", n,
                       means.size() / 4.0, color.size() / static_cast<double>(k), k);
  }
  if (basis.max_sh_degree < 0 || basis.max_sh_degree > 3 || basis.max_time_degree < 0 ||
      basis.max_time_degree > 2) {
    return fmt::format("colour basis out of range: SH degree {}, time degree {}",
                       basis.max_sh_degree, basis.max_time_degree);
  }
  return "";
}

}  // namespace hdr4d::method
