// The per-channel tone curves of the Dynamic Tone Mapper: g_c(x, f) = MLP(1+d -> H -> H -> 1,
// ReLU, sigmoid out) with x = log-HDR colour + log exposure and f the frame's context (H = 64 in
// the paper; three independent networks, one per RGB channel). Parameters per channel in
// MlpShape's flat layout (W1 H x (1+d) with column 0 for x, b1, W2, b2, W3, b3).
//
// Within one frame f is fixed, so each curve is a 1D function of x, and two paths evaluate it:
//   direct     the MLP on [x, f] for every value (ToneMapperConfig::tabulated = false);
//   tabulated  the pre-sigmoid output z at `table_nodes` uniform nodes over [kTableXMin,
//              kTableXMax], linear interpolation of z between a value's two nodes, then the
//              sigmoid; values outside the range use the direct path (exact).
// The table is built exactly and fast from the network's piecewise-linear form: with f folded
// into the first layer's bias (beff = b1 + W1[:, 1:] f), hidden unit o is relu(a_o x + beff_o),
// which switches at x = -beff_o / a_o. Between consecutive switch points the second layer's
// pre-activation is affine in x, u2 = alpha_s x + beta_s, so a node costs H multiply-adds
// instead of H^2, and the backward through the nodes sums per segment and reads, per hidden
// unit, the prefix (or suffix) of segments where that unit is on: O(nodes H + H^2) instead of
// O(nodes H^2). The interpolation is exact except in intervals that contain a switch point of
// either layer.
#pragma once

#include <cstddef>
#include <vector>

#include "method/tonemap/mlp.h"

namespace hdr4d::method {

// The table's x range: log radiance 1e-6..1e6 plus log exposure 1e-4..1e3 s
// (ln values -23.0 .. 20.7) with a margin.
inline constexpr double kTableXMin = -24.0;
inline constexpr double kTableXMax = 22.0;

struct ToneCurveShape {
  int context_size = 2;  // d
  int hidden = 64;       // H
  // Non-decreasing in x by construction (monotone_mlp.h): Prepare maps the stored parameters to
  // the effective ones, and every gradient these curves produce is with respect to the
  // effective parameters (DtmCore applies the chain rule to the stored ones).
  bool monotone = false;

  MlpShape Mlp() const { return {{1 + context_size, hidden, hidden, 1}, MlpOutput::kSigmoid}; }
  std::size_t NumParams() const { return Mlp().NumParams(); }
};

// One channel's curve for one frame (its parameters and f copied by Prepare).
template <typename T>
class FrameToneCurve {
 public:
  // table_nodes >= 2 builds the table; 0 prepares the direct path only. `params` are the stored
  // parameters (mapped to effective ones when shape.monotone).
  void Prepare(const ToneCurveShape& shape, const T* params, const T* f, int table_nodes);

  // ---- Direct path ---------------------------------------------------------------------------
  std::size_t DirectScratchSize() const;
  // y = g(x, f); `scratch` (DirectScratchSize()) keeps what DirectBackward needs.
  T Direct(T x, T* scratch) const;
  // For the scratch of Direct(x): ADDS dL/dparams (MlpShape layout) and dL/df; returns dL/dx.
  T DirectBackward(T dL_dy, T* scratch, T* dL_dparams, T* dL_df) const;

  // ---- Tabulated path ------------------------------------------------------------------------
  int nodes() const { return static_cast<int>(z_.size()); }
  bool InTable(T x) const { return x >= T(kTableXMin) && x <= T(kTableXMax); }
  // Interval j (0 .. nodes-2) holding x (InTable) and the weight w of node j+1.
  void Locate(T x, int* j, T* w) const {
    const T u = (x - T(kTableXMin)) * inv_step_;
    int k = static_cast<int>(u);
    k = k < last_interval_ ? k : last_interval_;
    *j = k;
    *w = u - T(k);
  }
  T TablePreSigmoid(int j, T w) const { return z_[j] + w * dz_[j]; }
  T TableSlope(int j) const { return dz_[j] * inv_step_; }  // dz/dx inside interval j
  double NodeX(int j) const { return kTableXMin + j * step_; }
  const std::vector<T>& node_values() const { return z_; }
  // Backward through the nodes: dL/dz per node -> ADDS dL/dparams and dL/df (exact).
  void TableBackward(const double* dL_dz, T* dL_dparams, T* dL_df) const;

  // The exact pre-sigmoid output at x from the piecewise-linear form (what the nodes hold).
  double PiecewiseLinear(double x) const;

 private:
  int Segment(double x) const;  // switch points strictly below x
  // Prepare's table, in steps: the first layer folded with f (a_, beff_), the switching units in
  // order (order_, rank_, switch_x_), each segment's alpha, beta, then the nodes.
  void FoldFirstLayer();
  void SortSwitchPoints();
  void BuildSegments();
  void TabulateNodes(int table_nodes);
  // TableBackward's sums over the nodes with a gradient: per segment s, row s + 1 of A (sum of
  // G2_j x_j) and B (sum of G2_j), G2_j the gradient at the second layer's pre-activation of node
  // j, then prefix sums over the rows; and the gradients of w3, b2 and b3.
  struct TableSums {
    std::vector<double> A, B, g_w3, g_b2;
    double g_b3 = 0.0;
  };
  TableSums SegmentSums(const double* dL_dz) const;
  // The first two layers' share of TableBackward: ADDS to W1, b1, W2 in dL_dparams and to g_f.
  void FirstLayersBackward(const TableSums& sums, T* dL_dparams, double* g_f) const;

  ToneCurveShape shape_;
  MlpShape mlp_;
  std::vector<T> params_, f_;
  // Piecewise-linear form (double): first-layer slope and folded bias, the switching units in
  // order of their switch points, and each segment's alpha, beta (segments x H).
  std::vector<double> a_, beff_, switch_x_, alpha_, beta_;
  std::vector<int> order_, rank_;  // rank_[o]: position of unit o in order_, -1 if a_o == 0
  // The table.
  std::vector<T> z_, dz_;  // node values; dz_[j] = z_[j+1] - z_[j]
  std::vector<int> node_segment_;
  double step_ = 0.0;
  T inv_step_ = T(0);
  int last_interval_ = 0;
};

extern template class FrameToneCurve<float>;
extern template class FrameToneCurve<double>;

}  // namespace hdr4d::method
