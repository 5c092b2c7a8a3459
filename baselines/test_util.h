// Helpers shared by the baselines' tests: random inputs and a finite-difference check of a
// function of a flat vector written as a weighted sum of its outputs.
#pragma once

#include <cmath>
#include <cstddef>
#include <functional>
#include <random>
#include <vector>

#include "tests/finite_difference.h"

namespace hdr4d::baselines::testing {

template <typename T = double>
std::vector<T> Uniform(std::size_t n, double lo, double hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<T> v(n);
  for (T& x : v) x = T(u(rng));
  return v;
}

inline hdr4d::testing::FdVector ToFd(const std::vector<double>& v) {
  return Eigen::Map<const hdr4d::testing::FdVector>(v.data(), Eigen::Index(v.size()));
}

inline std::vector<double> FromFd(const hdr4d::testing::FdVector& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}

// sum_k weights[k] * outputs[k].
inline double Dot(const std::vector<double>& weights, const std::vector<double>& outputs) {
  double s = 0.0;
  for (std::size_t k = 0; k < weights.size(); ++k) s += weights[k] * outputs[k];
  return s;
}

// Central-difference gradient of loss(v) at v (step h), compared with `analytic`.
inline void ExpectFdMatch(const std::function<double(const std::vector<double>&)>& loss,
                          const std::vector<double>& at,
                          const std::vector<double>& analytic,
                          double h = 1e-6,
                          double tolerance = 1e-6) {
  const auto numeric = hdr4d::testing::NumericGradient(
      [&](const hdr4d::testing::FdVector& x) { return loss(FromFd(x)); }, ToFd(at), h);
  hdr4d::testing::ExpectGradientsMatch(ToFd(analytic), numeric, tolerance);
}

template <typename T>
bool AllFiniteIn01(const std::vector<T>& v) {
  for (T x : v) {
    if (!std::isfinite(x) || x < T(0) || x > T(1)) return false;
  }
  return true;
}

template <typename T>
bool AllFinite(const std::vector<T>& v) {
  for (T x : v) {
    if (!std::isfinite(x)) return false;
  }
  return true;
}

}  // namespace hdr4d::baselines::testing
