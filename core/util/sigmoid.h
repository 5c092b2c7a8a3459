// The logistic function, defined once (and softplus, log(1 + e^x), beside it). Two spellings
// because saved runs must reproduce bit for bit: Sigmoid is the reference's opacity activation, 1 / (1 + e^-x); StableSigmoid is what the
// tone mappers' MLP heads use, evaluating e^x for negative x so it never takes the exponential of
// a large positive number. They agree to the last bit or two.
#pragma once

#include <cmath>

namespace hdr4d {

template <typename T>
inline T Sigmoid(T x) {
  return T(1) / (T(1) + std::exp(-x));
}

template <typename T>
inline T StableSigmoid(T z) {
  if (z >= T(0)) return T(1) / (T(1) + std::exp(-z));
  const T e = std::exp(z);
  return e / (T(1) + e);
}

// log(1 + e^z) for any finite z: never the exponential of a large positive number.
template <typename T>
inline T Softplus(T z) {
  return z > T(0) ? z + std::log1p(std::exp(-z)) : std::log1p(std::exp(z));
}

}  // namespace hdr4d
