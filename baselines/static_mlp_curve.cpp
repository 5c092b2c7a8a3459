#include "baselines/static_mlp_curve.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/util/error.h"

namespace hdr4d::baselines {

template <typename T>
StaticMlpCurve<T>::StaticMlpCurve(const T* params, int hidden) : hidden_(hidden) {
  HDR4D_CHECK(hidden > 0);
  w_.assign(params, params + hidden);
  b_.assign(params + hidden, params + 2 * hidden);
  v_.assign(params + 2 * hidden, params + 3 * hidden);
  const double c = double(params[3 * hidden]);
  std::vector<double> at(hidden);
  for (int j = 0; j < hidden; ++j) {
    if (w_[j] != 0.0) {
      order_.push_back(j);
      at[j] = -b_[j] / w_[j];
    }
  }
  // Stable order of equal switch points, so the build does not depend on the sort's whims.
  std::stable_sort(order_.begin(), order_.end(), [&](int i, int j) { return at[i] < at[j]; });
  switch_x_.resize(order_.size());
  for (std::size_t k = 0; k < order_.size(); ++k) switch_x_[k] = T(at[order_[k]]);
  // Below every switch point: the units that switch off (w < 0) are on, and the constant ones.
  double alpha = 0.0, beta = c;
  for (int j = 0; j < hidden; ++j) {
    if (w_[j] < 0.0 || (w_[j] == 0.0 && b_[j] > 0.0)) {
      alpha += v_[j] * w_[j];
      beta += v_[j] * b_[j];
    }
  }
  alpha_.push_back(T(alpha));
  beta_.push_back(T(beta));
  for (int j : order_) {
    const double sign = w_[j] > 0.0 ? 1.0 : -1.0;  // switches on, or off, going up in x
    alpha += sign * v_[j] * w_[j];
    beta += sign * v_[j] * b_[j];
    alpha_.push_back(T(alpha));
    beta_.push_back(T(beta));
  }
  // Buckets: about four per switch point over the finite range they span.
  const std::size_t n = switch_x_.size();
  if (n >= 2 && std::isfinite(double(switch_x_.front())) &&
      std::isfinite(double(switch_x_.back())) && switch_x_.back() > switch_x_.front()) {
    const int buckets = int(4 * n);
    bucket_lo_ = switch_x_.front();
    bucket_hi_ = switch_x_.back();
    const double width = (double(bucket_hi_) - double(bucket_lo_)) / buckets;
    inv_bucket_width_ = T(1.0 / width);
    bucket_start_.resize(buckets);
    for (int k = 0; k < buckets; ++k) {
      // Never past a value in the bucket: the edge is rounded down to T first.
      const T edge = T(double(bucket_lo_) + k * width);
      bucket_start_[k] = static_cast<int>(
          std::lower_bound(switch_x_.begin(), switch_x_.end(), edge) - switch_x_.begin());
    }
  }
}

template <typename T>
int StaticMlpCurve<T>::Segment(T x) const {
  if (x >= bucket_lo_ && x <= bucket_hi_) {
    int k = static_cast<int>((x - bucket_lo_) * inv_bucket_width_);
    k = std::min(k, static_cast<int>(bucket_start_.size()) - 1);
    int s = bucket_start_[k];
    // Exact whatever the rounding of the bucket index: step to the first switch point >= x.
    while (s > 0 && switch_x_[s - 1] >= x) --s;
    while (s < static_cast<int>(switch_x_.size()) && switch_x_[s] < x) ++s;
    return s;
  }
  return static_cast<int>(std::lower_bound(switch_x_.begin(), switch_x_.end(), x) -
                          switch_x_.begin());
}

template <typename T>
void StaticMlpCurve<T>::Backward(const double* s0, const double* s1, T* dL_dparams) const {
  const int n = segments();
  // prefix0[s] = sum of s0 over segments < s (n + 1 entries); likewise prefix1.
  std::vector<double> prefix0(n + 1, 0.0), prefix1(n + 1, 0.0);
  for (int s = 0; s < n; ++s) {
    prefix0[s + 1] = prefix0[s] + s0[s];
    prefix1[s + 1] = prefix1[s] + s1[s];
  }
  T* dw = dL_dparams;
  T* db = dL_dparams + hidden_;
  T* dv = dL_dparams + 2 * hidden_;
  auto add = [&](int j, double a0, double a1) {
    dv[j] += T(w_[j] * a1 + b_[j] * a0);
    dw[j] += T(v_[j] * a1);
    db[j] += T(v_[j] * a0);
  };
  for (std::size_t k = 0; k < order_.size(); ++k) {
    const int j = order_[k];
    if (w_[j] > 0.0) {  // on in segments k + 1 .. n - 1
      add(j, prefix0[n] - prefix0[k + 1], prefix1[n] - prefix1[k + 1]);
    } else {  // on in segments 0 .. k
      add(j, prefix0[k + 1], prefix1[k + 1]);
    }
  }
  for (int j = 0; j < hidden_; ++j) {
    if (w_[j] == 0.0 && b_[j] > 0.0) add(j, prefix0[n], prefix1[n]);  // always on
  }
  dL_dparams[3 * hidden_] += T(prefix0[n]);
}

template class StaticMlpCurve<float>;
template class StaticMlpCurve<double>;

}  // namespace hdr4d::baselines
