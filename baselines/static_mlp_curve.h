// A fast exact evaluation of one channel of the static MLP tone mapper (1 -> H -> 1, ReLU,
// sigmoid). Before its sigmoid the network is z(x) = c + sum_j v_j relu(w_j x + b_j), piecewise
// linear in x with a kink where each hidden unit switches (x = -b_j / w_j). Between consecutive
// switch points z = alpha_s x + beta_s; sorting the switch points once per call turns each value
// into a binary search and one multiply-add instead of 3H operations.
//
// The backward needs only two sums per segment s over the values that fall in it, S0_s = sum
// dL/dz and S1_s = sum dL/dz x: a unit that switches on at its switch point is active in every
// segment above it (a suffix of segments), one that switches off in every segment below (a
// prefix), so its gradients are dL/dv_j = w_j A1 + b_j A0, dL/dw_j = v_j A1, dL/db_j = v_j A0
// with A0, A1 the sums of S0, S1 over its active segments. That is the MLP's exact gradient (same
// maths as method::MlpBackward), in O(H) per channel after the values are binned.
//
// Segment lookup: a uniform grid of buckets over the switch points' range stores the segment at
// each bucket's left edge, so a value starts there and steps over the few switch points in its
// bucket (values outside that range, and curves with infinite switch points, binary-search).
//
// Same convention as method::MlpForward: a unit whose pre-activation is exactly 0 is off. At a
// value exactly on a switch point the segment below is used (z is continuous there; only the
// one-sided derivative differs, a measure-zero choice).
#pragma once

#include <cstddef>
#include <vector>

namespace hdr4d::baselines {

template <typename T>
class StaticMlpCurve {
 public:
  // params: one channel's network in method::MlpShape's layout for {1, hidden, 1}: w (hidden),
  // b (hidden), v (hidden), c.
  StaticMlpCurve(const T* params, int hidden);

  int segments() const { return static_cast<int>(alpha_.size()); }
  // The segment holding x (0 .. segments() - 1): the number of switch points below x.
  int Segment(T x) const;
  T PreSigmoid(T x, int segment) const { return alpha_[segment] * x + beta_[segment]; }
  T Slope(int segment) const { return alpha_[segment]; }  // dz/dx in the segment

  // ADDS dL/dparams (the layout above) from the per-segment sums s0 = sum dL/dz and
  // s1 = sum dL/dz * x (segments() values each).
  void Backward(const double* s0, const double* s1, T* dL_dparams) const;

 private:
  int hidden_;
  std::vector<double> w_, b_, v_;
  std::vector<T> switch_x_;  // sorted switch points of the units with w != 0
  std::vector<int> order_;   // units in that order
  std::vector<T> alpha_, beta_;
  T bucket_lo_ = T(0), bucket_hi_ = T(-1), inv_bucket_width_ = T(0);  // empty when lo > hi
  std::vector<int> bucket_start_;
};

extern template class StaticMlpCurve<float>;
extern template class StaticMlpCurve<double>;

}  // namespace hdr4d::baselines
