#include "method/tonemap/tone_curve.h"

#include <algorithm>
#include <numeric>

#include "core/util/error.h"
#include "method/tonemap/monotone_mlp.h"

namespace hdr4d::method {

// Parameter offsets inside one channel's MlpShape layout.
namespace {
struct CurveLayout {
  std::size_t w1, b1, w2, b2, w3, b3;
  int in, h;
  explicit CurveLayout(const ToneCurveShape& s) : in(1 + s.context_size), h(s.hidden) {
    w1 = 0;
    b1 = w1 + std::size_t(h) * in;
    w2 = b1 + h;
    b2 = w2 + std::size_t(h) * h;
    w3 = b2 + h;
    b3 = w3 + h;
  }
};
}  // namespace

template <typename T>
void FrameToneCurve<T>::Prepare(const ToneCurveShape& shape,
                                const T* stored,
                                const T* f,
                                int table_nodes) {
  HDR4D_CHECK(table_nodes == 0 || table_nodes >= 2);
  shape_ = shape;
  mlp_ = shape.Mlp();
  params_.assign(stored, stored + shape.NumParams());
  if (shape.monotone) MonotoneEffective(mlp_, stored, params_.data());
  f_.assign(f, f + shape.context_size);
  z_.clear();
  dz_.clear();
  node_segment_.clear();
  if (table_nodes == 0) return;
  FoldFirstLayer();
  SortSwitchPoints();
  BuildSegments();
  TabulateNodes(table_nodes);
}

template <typename T>
void FrameToneCurve<T>::FoldFirstLayer() {
  const CurveLayout L(shape_);
  const int H = L.h, d = shape_.context_size;
  const T* params = params_.data();  // effective
  const T* W1 = params + L.w1;
  a_.assign(H, 0.0);
  beff_.assign(H, 0.0);
  for (int o = 0; o < H; ++o) {
    a_[o] = double(W1[o * L.in]);
    double b = double(params[L.b1 + o]);
    for (int k = 0; k < d; ++k) b += double(W1[o * L.in + 1 + k]) * double(f_[k]);
    beff_[o] = b;
  }
}

template <typename T>
void FrameToneCurve<T>::SortSwitchPoints() {
  const int H = shape_.hidden;
  // Switching units sorted by switch point (ties by unit index: deterministic).
  order_.clear();
  rank_.assign(H, -1);
  for (int o = 0; o < H; ++o) {
    if (a_[o] != 0.0) order_.push_back(o);
  }
  std::vector<double> x_switch(H, 0.0);
  for (int o : order_) x_switch[o] = -beff_[o] / a_[o];
  std::sort(order_.begin(), order_.end(), [&](int p, int q) {
    return x_switch[p] != x_switch[q] ? x_switch[p] < x_switch[q] : p < q;
  });
  switch_x_.resize(order_.size());
  for (std::size_t i = 0; i < order_.size(); ++i) {
    rank_[order_[i]] = static_cast<int>(i);
    switch_x_[i] = x_switch[order_[i]];
  }
}

template <typename T>
void FrameToneCurve<T>::BuildSegments() {
  const CurveLayout L(shape_);
  const int H = L.h;
  const T* params = params_.data();  // effective
  const T* W2 = params + L.w2;
  // Segment 0 (x below every switch point): units with a < 0 are on, constant units when
  // beff > 0. Each later segment toggles one unit.
  const int S = static_cast<int>(order_.size()) + 1;
  alpha_.assign(std::size_t(S) * H, 0.0);
  beta_.assign(std::size_t(S) * H, 0.0);
  for (int k = 0; k < H; ++k) beta_[k] = double(params[L.b2 + k]);
  for (int o = 0; o < H; ++o) {
    const bool on = a_[o] < 0.0 || (a_[o] == 0.0 && beff_[o] > 0.0);
    if (!on) continue;
    for (int k = 0; k < H; ++k) {
      alpha_[k] += double(W2[k * H + o]) * a_[o];
      beta_[k] += double(W2[k * H + o]) * beff_[o];
    }
  }
  for (int s = 1; s < S; ++s) {
    const int o = order_[s - 1];
    const double sign = a_[o] > 0.0 ? 1.0 : -1.0;  // turns on (a > 0) or off (a < 0)
    const double* pa = alpha_.data() + std::size_t(s - 1) * H;
    const double* pb = beta_.data() + std::size_t(s - 1) * H;
    double* na = alpha_.data() + std::size_t(s) * H;
    double* nb = beta_.data() + std::size_t(s) * H;
    for (int k = 0; k < H; ++k) {
      const double w = sign * double(W2[k * H + o]);
      na[k] = pa[k] + w * a_[o];
      nb[k] = pb[k] + w * beff_[o];
    }
  }
}

template <typename T>
void FrameToneCurve<T>::TabulateNodes(int table_nodes) {
  const CurveLayout L(shape_);
  const int H = L.h, S = static_cast<int>(order_.size()) + 1;
  const T* params = params_.data();  // effective
  // Nodes, swept in order with the segments.
  step_ = (kTableXMax - kTableXMin) / (table_nodes - 1);
  inv_step_ = T(1.0 / step_);
  last_interval_ = table_nodes - 2;
  z_.resize(table_nodes);
  dz_.resize(table_nodes - 1);
  node_segment_.resize(table_nodes);
  const T* w3 = params + L.w3;
  int s = 0;
  for (int j = 0; j < table_nodes; ++j) {
    while (s < S - 1 && switch_x_[s] < NodeX(j)) ++s;
    node_segment_[j] = s;
  }
  // Per run of nodes in one segment, unit by unit: a branch-free loop over the nodes.
  std::vector<double> x(table_nodes), z(table_nodes, double(params[L.b3]));
  for (int j = 0; j < table_nodes; ++j) x[j] = NodeX(j);
  for (int j0 = 0; j0 < table_nodes;) {
    int j1 = j0;
    while (j1 < table_nodes && node_segment_[j1] == node_segment_[j0]) ++j1;
    const double* al = alpha_.data() + std::size_t(node_segment_[j0]) * H;
    const double* be = beta_.data() + std::size_t(node_segment_[j0]) * H;
    for (int k = 0; k < H; ++k) {
      const double a = al[k], b = be[k], w = double(w3[k]);
      for (int j = j0; j < j1; ++j) z[j] += w * std::max(a * x[j] + b, 0.0);
    }
    j0 = j1;
  }
  for (int j = 0; j < table_nodes; ++j) z_[j] = T(z[j]);
  for (int j = 0; j + 1 < table_nodes; ++j) dz_[j] = z_[j + 1] - z_[j];
}

template <typename T>
int FrameToneCurve<T>::Segment(double x) const {
  return static_cast<int>(std::lower_bound(switch_x_.begin(), switch_x_.end(), x) -
                          switch_x_.begin());
}

template <typename T>
double FrameToneCurve<T>::PiecewiseLinear(double x) const {
  HDR4D_CHECK(!z_.empty());
  const CurveLayout L(shape_);
  const int H = L.h, s = Segment(x);
  double z = double(params_[L.b3]);
  for (int k = 0; k < H; ++k) {
    const double u = alpha_[std::size_t(s) * H + k] * x + beta_[std::size_t(s) * H + k];
    if (u > 0.0) z += double(params_[L.w3 + k]) * u;
  }
  return z;
}

template <typename T>
void FrameToneCurve<T>::TableBackward(const double* dL_dz, T* dL_dparams, T* dL_df) const {
  HDR4D_CHECK(!z_.empty());
  const CurveLayout L(shape_);
  const int H = L.h, d = shape_.context_size;
  const TableSums sums = SegmentSums(dL_dz);
  std::vector<double> g_f(d, 0.0);
  FirstLayersBackward(sums, dL_dparams, g_f.data());
  for (int k = 0; k < H; ++k) {
    dL_dparams[L.b2 + k] += T(sums.g_b2[k]);
    dL_dparams[L.w3 + k] += T(sums.g_w3[k]);
  }
  dL_dparams[L.b3] += T(sums.g_b3);
  for (int k = 0; k < d; ++k) dL_df[k] += T(g_f[k]);
}

template <typename T>
typename FrameToneCurve<T>::TableSums FrameToneCurve<T>::SegmentSums(const double* dL_dz) const {
  const CurveLayout L(shape_);
  const int H = L.h, S = static_cast<int>(order_.size()) + 1;
  const T* w3 = params_.data() + L.w3;
  TableSums t;
  t.A.assign(std::size_t(S + 1) * H, 0.0);
  t.B.assign(std::size_t(S + 1) * H, 0.0);
  t.g_w3.assign(H, 0.0);
  t.g_b2.assign(H, 0.0);
  int first = nodes(), last = -1;  // the nodes with a gradient
  for (int j = 0; j < nodes(); ++j) {
    if (dL_dz[j] != 0.0) {
      first = std::min(first, j);
      last = j;
      t.g_b3 += dL_dz[j];
    }
  }
  // Per run of nodes in one segment, unit by unit (branch-free over the nodes): the sums of
  // g_j and g_j x_j over the nodes where the unit's second-layer pre-activation is positive.
  for (int j0 = first; j0 <= last;) {
    int j1 = j0;
    while (j1 <= last && node_segment_[j1] == node_segment_[j0]) ++j1;
    const int s = node_segment_[j0];
    const double* al = alpha_.data() + std::size_t(s) * H;
    const double* be = beta_.data() + std::size_t(s) * H;
    // Row s + 1 of A and B: they become prefix sums below (row 0 stays zero).
    double* As = t.A.data() + std::size_t(s + 1) * H;
    double* Bs = t.B.data() + std::size_t(s + 1) * H;
    for (int k = 0; k < H; ++k) {
      const double a = al[k], b = be[k];
      double sum_gu = 0.0, sum_g = 0.0, sum_gx = 0.0;
      for (int j = j0; j < j1; ++j) {
        const double x = NodeX(j), u = a * x + b;
        const double g = u > 0.0 ? dL_dz[j] : 0.0;
        sum_gu += g * u;
        sum_g += g;
        sum_gx += g * x;
      }
      const double w = double(w3[k]);
      t.g_w3[k] += sum_gu;
      t.g_b2[k] += w * sum_g;
      As[k] += w * sum_gx;
      Bs[k] += w * sum_g;
    }
    j0 = j1;
  }
  for (int s = 1; s <= S; ++s) {  // prefix sums: row s = segments 0 .. s-1
    for (int k = 0; k < H; ++k) {
      t.A[std::size_t(s) * H + k] += t.A[std::size_t(s - 1) * H + k];
      t.B[std::size_t(s) * H + k] += t.B[std::size_t(s - 1) * H + k];
    }
  }
  return t;
}

template <typename T>
void FrameToneCurve<T>::FirstLayersBackward(const TableSums& t, T* dL_dparams, double* g_f) const {
  const CurveLayout L(shape_);
  const int H = L.h, d = shape_.context_size, S = static_cast<int>(order_.size()) + 1;
  const T* W1 = params_.data() + L.w1;
  const T* W2 = params_.data() + L.w2;
  const double* A_all = t.A.data() + std::size_t(S) * H;
  const double* B_all = t.B.data() + std::size_t(S) * H;
  std::vector<double> SA(H), SB(H);
  T* dW1 = dL_dparams + L.w1;
  T* dW2 = dL_dparams + L.w2;
  for (int o = 0; o < H; ++o) {
    // The segments where unit o is on: a suffix (a > 0), a prefix (a < 0), all or none (a = 0).
    const int r = rank_[o];
    if (a_[o] > 0.0) {
      for (int k = 0; k < H; ++k) {
        SA[k] = A_all[k] - t.A[std::size_t(r + 1) * H + k];
        SB[k] = B_all[k] - t.B[std::size_t(r + 1) * H + k];
      }
    } else if (a_[o] < 0.0) {
      for (int k = 0; k < H; ++k) {
        SA[k] = t.A[std::size_t(r + 1) * H + k];
        SB[k] = t.B[std::size_t(r + 1) * H + k];
      }
    } else if (beff_[o] > 0.0) {
      std::copy(A_all, A_all + H, SA.begin());
      std::copy(B_all, B_all + H, SB.begin());
    } else {
      continue;
    }
    double g_a = 0.0, g_beff = 0.0;
    for (int k = 0; k < H; ++k) {
      const double w = double(W2[k * H + o]);
      dW2[k * H + o] += T(a_[o] * SA[k] + beff_[o] * SB[k]);
      g_a += w * SA[k];
      g_beff += w * SB[k];
    }
    // Unfold beff = b1 + W1[:, 1:] f.
    dW1[o * L.in] += T(g_a);
    dL_dparams[L.b1 + o] += T(g_beff);
    for (int k = 0; k < d; ++k) {
      dW1[o * L.in + 1 + k] += T(g_beff * double(f_[k]));
      g_f[k] += g_beff * double(W1[o * L.in + 1 + k]);
    }
  }
}

// Direct scratch layout: input [x, f] | activation cache | backward scratch | dL/dinput.
template <typename T>
std::size_t FrameToneCurve<T>::DirectScratchSize() const {
  return 2 * std::size_t(mlp_.inputs()) + mlp_.CacheSize() + 2 * std::size_t(mlp_.MaxWidth());
}

template <typename T>
T FrameToneCurve<T>::Direct(T x, T* scratch) const {
  T* in = scratch;
  T* cache = in + mlp_.inputs();
  in[0] = x;
  std::copy(f_.begin(), f_.end(), in + 1);
  T y;
  MlpForward(mlp_, params_.data(), in, &y, cache);
  return y;
}

template <typename T>
T FrameToneCurve<T>::DirectBackward(T dL_dy, T* scratch, T* dL_dparams, T* dL_df) const {
  const T* in = scratch;
  const T* cache = in + mlp_.inputs();
  T* back = scratch + mlp_.inputs() + mlp_.CacheSize();
  T* d_in = back + 2 * std::size_t(mlp_.MaxWidth());
  MlpBackward(mlp_, params_.data(), in, cache, &dL_dy, d_in, dL_dparams, back);
  for (int k = 0; k < shape_.context_size; ++k) dL_df[k] += d_in[1 + k];
  return d_in[0];
}

template class FrameToneCurve<float>;
template class FrameToneCurve<double>;

}  // namespace hdr4d::method
