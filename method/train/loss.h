// The photometric training loss of 3DGS / 4DGS / HDR-4DGS (ARCHITECTURE §4 "Losses") and its backward:
//   L(pred, gt) = (1 - lambda) L1 + lambda (1 - SSIM),   lambda = 0.2 by default,
// L1 = mean |pred - gt| over pixels and channels, SSIM = the windowed SSIM of hdr4d::Ssim
// (core/metrics/metrics.h): 11x11 Gaussian window (sigma 1.5), c1 = 0.01^2, c2 = 0.03^2, zero-padded
// "same"-size maps, each channel on its own, mean over pixels and channels.
//
// Backward: SSIM at a pixel is a function of five window sums (mu_x, mu_y, E[x^2], E[y^2], E[xy]).
// Its partial derivatives with respect to the sums of pred (mu_x, E[x^2], E[xy]) are formed per
// pixel and filtered once more with the same window; with zero padding and a symmetric window,
// the transposed filter is the filter itself. Then
//   d mean(SSIM) / d x_q = (1/N) [ G*P_mu + 2 x_q G*P_xx + y_q G*P_xy ](q).
// L1's subgradient at pred == gt is 0 (sign(0) = 0, as in torch).
//
// Images are interleaved H x W x C (index (y * W + x) * C + c), any channel count. Rows run in
// parallel (core/util/parallel.h); every per-row quantity is reduced in row order, so the value and
// the gradient are bit-identical at any thread count. Working memory (8 image-sized maps) is kept
// per calling thread and reused, so repeated calls at one size do not allocate.
#pragma once

namespace hdr4d::method {

inline constexpr float kDefaultLambdaDssim = 0.2f;

struct LossResult {
  double value = 0.0;  // (1 - lambda) l1 + lambda (1 - ssim)
  double l1 = 0.0;     // mean absolute difference
  double ssim = 0.0;   // mean SSIM
};

// The loss of `pred` against `gt`, both width x height x channels interleaved. When `dL_dpred`
// is non-null it is overwritten (not accumulated) with d value / d pred, same layout.
// width, height, channels must be positive and lambda_dssim in [0, 1] (checked: a caller bug).
// Inputs are not checked for NaN; a NaN gives a NaN loss and gradient (the trainer checks
// gradients with AllFinite, method/optim/adam.h, before stepping).
LossResult PhotometricLoss(const float* pred,
                           const float* gt,
                           int width,
                           int height,
                           int channels,
                           float lambda_dssim,
                           float* dL_dpred);

// The same computation carried out entirely in double (finite-difference tests, references).
LossResult PhotometricLoss(const double* pred,
                           const double* gt,
                           int width,
                           int height,
                           int channels,
                           double lambda_dssim,
                           double* dL_dpred);

}  // namespace hdr4d::method
