// The 4D or 3D preprocess vectorised over Gaussians (preprocess_simd.h): one Gaussian per lane,
// the formulas of rotation4d.h, slice.h, projection.h and sh4d.h written out entry by entry. The
// backward recomputes the forward's geometry (cheaper than storing 45 floats per Gaussian) with
// the same code, so both see identical values.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "method/render/preprocess_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
// Must come after foreach_target.h.
#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

#include <cmath>
#include <cstring>
#include <initializer_list>
#include <numbers>
#include <utility>

#include "method/gaussian/constants.h"
#include "method/gaussian/sh4d.h"
#include "method/gaussian/slice.h"
#include "method/render/preprocess_simd.h"

HWY_BEFORE_NAMESPACE();
namespace hdr4d::method::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::CappedTag<float, kPreprocessBatch>;
using DI = hn::RebindToSigned<D>;
using V = hn::Vec<D>;
using M = hn::Mask<D>;
constexpr int kB = kPreprocessBatch;

// One batch's parameters as structure of arrays; padded lanes are zeros (culled: p(t) = 0 there
// is irrelevant, every lane past `count` is ignored).
struct BatchIn {
  HWY_ALIGN float mean[4][kB];
  HWY_ALIGN float scale[4][kB];
  HWY_ALIGN float ql[4][kB];
  HWY_ALIGN float qr[4][kB];
  HWY_ALIGN float logit[kB];
};

void LoadBatch(const PreprocessSimdJob& job, const std::int64_t* index, int count, BatchIn* in) {
  if (count < kB) std::memset(in, 0, sizeof(BatchIn));
  for (int l = 0; l < count; ++l) {
    const std::size_t i = static_cast<std::size_t>(index[l]);
    for (int k = 0; k < 3; ++k) in->mean[k][l] = job.xyz[3 * i + k];
    in->mean[3][l] = job.t[i];
    for (int k = 0; k < 4; ++k) {
      in->scale[k][l] = job.log_scales[4 * i + k];
      in->ql[k][l] = job.rot_left[4 * i + k];
      in->qr[k][l] = job.rot_right[4 * i + k];
    }
    in->logit[l] = job.opacity_logit[i];
  }
}

// 2^x for x <= 0 (whole part >= -126), from above: 2^n times the degree-3 Taylor polynomial
// of 2^f, |f| <= 1/2, whose error is below 6.2e-4 of the value, times 1 + 1e-3. For bounds only.
HWY_INLINE V Exp2Above(V x) {
  const D d;
  const DI di;
  const V n = hn::Round(x);
  const V r = hn::Mul(hn::Sub(x, n), hn::Set(d, 0.693147180559945309f));
  V p = hn::MulAdd(r, hn::Set(d, 1.0f / 6.0f), hn::Set(d, 0.5f));
  p = hn::MulAdd(hn::MulAdd(p, r, hn::Set(d, 1.0f)), r, hn::Set(d, 1.0f));
  const V two_n = hn::BitCast(
      d, hn::ShiftLeft<23>(hn::BitCast(di, hn::Add(n, hn::Set(d, 12582912.0f + 127.0f)))));
  return hn::Mul(hn::Mul(p, two_n), hn::Set(d, 1.001f));
}

// Which of the Gaussians [begin, begin + count) may be visible at the view's time. A Gaussian
// whose marginal p(t) = exp(-dt^2 / 2 Sigma_tt) is surely at or below kTemporalCullMarginal,
// i.e. dt^2 >= 2 ln(1 / threshold) Sigma_tt, gets the forward's outputs of a culled one here
// (zero radii), without its geometry; the others' indices go to `kept`, for ForwardBatch.
// Sigma_tt = sum_k R(3, k)^2 exp(2 s_k) (floored as in SlicedGeometry) is bounded from above:
// the row of the 4D rotation from the unnormalised quaternions, divided once by both squared
// norms, the exponentials from above (Exp2Above), and a margin of 1% over all (the full test's
// own rounding is about 1e-6 of it). So the cull removes only Gaussians the full test removes,
// and the results do not change. Lanes past the last whole vector, non-finite values, extreme
// values (see `ok`) and quaternions the kernels replace by the identity are kept.
int TemporalSurvivors(const PreprocessSimdJob& job,
                      std::int64_t begin,
                      int count,
                      std::int64_t* kept) {
  const D d;
  const DI di;
  const int lanes = static_cast<int>(hn::Lanes(d));
  int num_kept = 0;
  const auto keep = [&](std::int64_t i) { kept[num_kept++] = i; };
  if (!job.temporal) {
    for (int l = 0; l < count; ++l) keep(begin + l);
    return num_kept;
  }
  const float min_norm = static_cast<float>(kMinQuaternionNorm);
  const V min_norm2 = hn::Set(d, min_norm * min_norm);
  const V max_norm2 = hn::Set(d, 1e6f);
  // dt^2 / Sigma_tt above this: p(t) below the threshold.
  const V cut = hn::Set(d, 1.01f * 2.0f * std::log(1.0f / kTemporalCullMarginal));
  const V log2e2 = hn::Set(d, 2.0f * 1.44269504088896341f);
  int off = 0;
  for (; off + lanes <= count; off += lanes) {
    const std::size_t i0 = static_cast<std::size_t>(begin + off);
    V ql[4], qr[4], s[4];
    hn::LoadInterleaved4(d, job.rot_left + 4 * i0, ql[0], ql[1], ql[2], ql[3]);
    hn::LoadInterleaved4(d, job.rot_right + 4 * i0, qr[0], qr[1], qr[2], qr[3]);
    hn::LoadInterleaved4(d, job.log_scales + 4 * i0, s[0], s[1], s[2], s[3]);
    const auto norm2 = [](const V* q) {
      V n2 = hn::Mul(q[0], q[0]);
      for (int k = 1; k < 4; ++k) n2 = hn::MulAdd(q[k], q[k], n2);
      return n2;
    };
    const V n2l = norm2(ql), n2r = norm2(qr);
    // The bound is computed only where no step can overflow or meet a NaN: quaternions of
    // length between kMinQuaternionNorm and 1000, log-scales at most 40 (the others are kept).
    M ok = hn::And(hn::And(hn::Gt(n2l, min_norm2), hn::Lt(n2l, max_norm2)),
                   hn::And(hn::Gt(n2r, min_norm2), hn::Lt(n2r, max_norm2)));
    for (int k = 0; k < 4; ++k) ok = hn::And(ok, hn::Le(s[k], hn::Set(d, 40.0f)));
    // Row 0 of M_l (LeftIsoclinic) times M_r (RightIsoclinic): A(0, j) = R(3, 3 - j).
    const V ml0[4] = {ql[0], hn::Neg(ql[1]), hn::Neg(ql[2]), hn::Neg(ql[3])};
    const V p = qr[0], x = qr[1], y = qr[2], z = qr[3];
    const V mr[4][4] = {{p, x, y, z},
                        {hn::Neg(x), p, hn::Neg(z), y},
                        {hn::Neg(y), z, p, hn::Neg(x)},
                        {hn::Neg(z), hn::Neg(y), x, p}};
    V stt = hn::Zero(d), trace = hn::Zero(d);
    for (int j = 0; j < 4; ++j) {
      V r = hn::Mul(ml0[0], mr[0][j]);
      for (int k = 1; k < 4; ++k) r = hn::MulAdd(ml0[k], mr[k][j], r);
      // exp(2 s) of axis 3 - j (2^-126 at least: Exp2Above's range; a bound from above).
      const V var = Exp2Above(hn::Max(hn::Mul(s[3 - j], log2e2), hn::Set(d, -126.0f)));
      stt = hn::MulAdd(hn::Mul(r, r), var, stt);
      trace = hn::Add(trace, var);
    }
    stt = hn::Div(stt, hn::Mul(n2l, n2r));
    const V floor = hn::MulAdd(hn::Set(d, static_cast<float>(kSliceRelativeVarianceFloor)), trace,
                               hn::Set(d, static_cast<float>(kSliceAbsoluteVarianceFloor)));
    const V dt = hn::Sub(hn::Set(d, job.time), hn::LoadU(d, job.t + i0));
    const M culled = hn::And(ok, hn::Gt(hn::Mul(dt, dt), hn::Mul(cut, hn::Max(stt, floor))));
    HWY_ALIGN std::int32_t flag[kB];
    hn::Store(hn::VecFromMask(di, hn::RebindMask(di, culled)), di, flag);
    for (int l = 0; l < lanes; ++l) {
      const std::size_t i = i0 + static_cast<std::size_t>(l);
      if (flag[l] == 0) {
        keep(static_cast<std::int64_t>(i));
        continue;
      }
      job.radius[i] = 0;
      job.reach[2 * i] = job.reach[2 * i + 1] = 0;
      job.screen_radius[i] = 0;
    }
  }
  for (; off < count; ++off) keep(begin + off);
  return num_kept;
}

// The forward's values of one vector of Gaussians that the backward needs as well.
struct Geometry {
  V ql[4], qr[4], ql_norm, qr_norm;
  M ql_ok, qr_ok;
  V R[4][4];  // 4D rotation (3D mode: the 3x3 block R[0..2][0..2])
  V var[4];   // exp(2 s) (3D mode: 0..2)
  V S[4][4];  // Sigma
  M floored;
  V stt_inv, dt;  // 1 / Sigma_tt (floored), t - mu_t
  V mean[3], cov[3][3], marginal;
  V p[3], inv_z, jx, jy;
  M clamped_x, clamped_y;
  V Mj[2][3];  // J R_view
  V u[2][3];   // cov M_k^T
  V a, b, c, det, lambda;
  V radius;  // 3-sigma screen radius (float, whole), 0 where not visible
  M visible;
};

HWY_INLINE V LoadRow(const float* row, int off) { return hn::Load(D(), row + off); }

// q / |q|, or the identity below kMinQuaternionNorm.
HWY_INLINE void Normalize(const float (*q)[kB], int off, V* out, V* norm, M* ok) {
  const D d;
  V n2 = hn::Mul(LoadRow(q[0], off), LoadRow(q[0], off));
  for (int k = 1; k < 4; ++k) n2 = hn::MulAdd(LoadRow(q[k], off), LoadRow(q[k], off), n2);
  *norm = hn::Sqrt(n2);
  *ok = hn::Gt(*norm, hn::Set(d, static_cast<float>(kMinQuaternionNorm)));
  for (int k = 0; k < 4; ++k) {
    const V v = hn::Div(LoadRow(q[k], off), *norm);
    out[k] = k == 0 ? hn::IfThenElse(*ok, v, hn::Set(d, 1.0f)) : hn::IfThenElseZero(*ok, v);
  }
}

// M_l(q_l) and M_r(q_r) of rotation4d.h.
HWY_INLINE void LeftIsoclinic(const V* q, V m[4][4]) {
  const V a = q[0], b = q[1], c = q[2], e = q[3];
  const V nb = hn::Neg(b), nc = hn::Neg(c), ne = hn::Neg(e);
  const V rows[4][4] = {{a, nb, nc, ne}, {b, a, ne, c}, {c, e, a, nb}, {e, nc, b, a}};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) m[i][j] = rows[i][j];
}
HWY_INLINE void RightIsoclinic(const V* q, V m[4][4]) {
  const V p = q[0], x = q[1], y = q[2], z = q[3];
  const V nx = hn::Neg(x), ny = hn::Neg(y), nz = hn::Neg(z);
  const V rows[4][4] = {{p, x, y, z}, {nx, p, nz, y}, {ny, z, p, nx}, {nz, ny, x, p}};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) m[i][j] = rows[i][j];
}

// 3D mode (rotation4d.h Rotation3D, Covariance3D): the rotation of q_l, Sigma3 = L L^T with
// L = R diag(exp(s)), the mean as it is and no marginal.
HWY_INLINE void StaticGeometry(const BatchIn& in, int off, Geometry* g) {
  const D d;
  Normalize(in.ql, off, g->ql, &g->ql_norm, &g->ql_ok);
  const V w = g->ql[0], x = g->ql[1], y = g->ql[2], z = g->ql[3];
  const V one = hn::Set(d, 1.0f), two = hn::Set(d, 2.0f);
  const auto twice = [&](V v) { return hn::Mul(two, v); };
  g->R[0][0] = hn::NegMulAdd(two, hn::MulAdd(y, y, hn::Mul(z, z)), one);
  g->R[0][1] = twice(hn::NegMulAdd(w, z, hn::Mul(x, y)));
  g->R[0][2] = twice(hn::MulAdd(w, y, hn::Mul(x, z)));
  g->R[1][0] = twice(hn::MulAdd(w, z, hn::Mul(x, y)));
  g->R[1][1] = hn::NegMulAdd(two, hn::MulAdd(x, x, hn::Mul(z, z)), one);
  g->R[1][2] = twice(hn::NegMulAdd(w, x, hn::Mul(y, z)));
  g->R[2][0] = twice(hn::NegMulAdd(w, y, hn::Mul(x, z)));
  g->R[2][1] = twice(hn::MulAdd(w, x, hn::Mul(y, z)));
  g->R[2][2] = hn::NegMulAdd(two, hn::MulAdd(x, x, hn::Mul(y, y)), one);
  V L[3][3];
  for (int k = 0; k < 3; ++k) {
    const V e = hn::Exp(d, hn::Min(LoadRow(in.scale[k], off), hn::Set(d, 88.0f)));
    g->var[k] = hn::Mul(e, e);
    for (int i = 0; i < 3; ++i) L[i][k] = hn::Mul(g->R[i][k], e);
  }
  for (int i = 0; i < 3; ++i) {
    g->mean[i] = LoadRow(in.mean[i], off);
    for (int j = i; j < 3; ++j) {
      V acc = hn::Mul(L[i][0], L[j][0]);
      for (int k = 1; k < 3; ++k) acc = hn::MulAdd(L[i][k], L[j][k], acc);
      g->cov[i][j] = g->cov[j][i] = acc;
    }
  }
  g->marginal = one;
  // The unused 4th axis as the identity, so no entry of the Geometry is left unset.
  for (int k = 0; k < 3; ++k) g->R[3][k] = g->R[k][3] = hn::Zero(d);
  g->R[3][3] = one;
  g->var[3] = one;
}

// 4D mode: the 4D rotation and covariance and the slice at t (rotation4d.h, slice.h).
HWY_INLINE void SlicedGeometry(const PreprocessSimdJob& job,
                               const BatchIn& in,
                               int off,
                               Geometry* g) {
  const D d;
  Normalize(in.ql, off, g->ql, &g->ql_norm, &g->ql_ok);
  Normalize(in.qr, off, g->qr, &g->qr_norm, &g->qr_ok);
  V ml[4][4], mr[4][4];
  LeftIsoclinic(g->ql, ml);
  RightIsoclinic(g->qr, mr);
  // R(i, j) = A(3 - i, 3 - j), A = M_l M_r.
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      V acc = hn::Mul(ml[i][0], mr[0][j]);
      for (int k = 1; k < 4; ++k) acc = hn::MulAdd(ml[i][k], mr[k][j], acc);
      g->R[3 - i][3 - j] = acc;
    }
  }
  // Sigma = L L^T, L = R diag(exp(s)).
  V L[4][4];
  for (int k = 0; k < 4; ++k) {
    const V e = hn::Exp(d, hn::Min(LoadRow(in.scale[k], off), hn::Set(d, 88.0f)));
    g->var[k] = hn::Mul(e, e);
    for (int i = 0; i < 4; ++i) L[i][k] = hn::Mul(g->R[i][k], e);
  }
  for (int i = 0; i < 4; ++i) {
    for (int j = i; j < 4; ++j) {
      V acc = hn::Mul(L[i][0], L[j][0]);
      for (int k = 1; k < 4; ++k) acc = hn::MulAdd(L[i][k], L[j][k], acc);
      g->S[i][j] = g->S[j][i] = acc;
    }
  }
  // Slice at t (slice.h).
  const V trace = hn::Add(hn::Add(hn::Add(g->S[0][0], g->S[1][1]), g->S[2][2]), g->S[3][3]);
  const V floor = hn::MulAdd(hn::Set(d, static_cast<float>(kSliceRelativeVarianceFloor)), trace,
                             hn::Set(d, static_cast<float>(kSliceAbsoluteVarianceFloor)));
  const V stt = g->S[3][3];
  g->floored = hn::Not(hn::Gt(stt, floor));
  g->stt_inv = hn::Div(hn::Set(d, 1.0f), hn::IfThenElse(g->floored, floor, stt));
  g->dt = hn::Sub(hn::Set(d, job.time), LoadRow(in.mean[3], off));
  const V dt_inv = hn::Mul(g->dt, g->stt_inv);
  for (int i = 0; i < 3; ++i) g->mean[i] = hn::MulAdd(g->S[i][3], dt_inv, LoadRow(in.mean[i], off));
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) {
      g->cov[i][j] = g->cov[j][i] =
          hn::NegMulAdd(hn::Mul(g->S[i][3], g->S[j][3]), g->stt_inv, g->S[i][j]);
    }
  }
  // exp(-0.5 dt^2 / stt) >= 0; below -87 it is culled anyway.
  g->marginal =
      hn::Exp(d, hn::Max(hn::Mul(hn::Mul(hn::Set(d, -0.5f), g->dt), dt_inv), hn::Set(d, -100.0f)));
}

HWY_INLINE void ComputeGeometry(const PreprocessSimdJob& job,
                                const BatchIn& in,
                                int off,
                                Geometry* g) {
  const D d;
  if (job.temporal) {
    SlicedGeometry(job, in, off, g);
  } else {
    StaticGeometry(in, off, g);
  }

  // EWA projection (projection.h).
  const float* vr = job.rotation;
  for (int i = 0; i < 3; ++i) {
    V acc = hn::MulAdd(hn::Set(d, vr[3 * i]), g->mean[0], hn::Set(d, job.translation[i]));
    acc = hn::MulAdd(hn::Set(d, vr[3 * i + 1]), g->mean[1], acc);
    g->p[i] = hn::MulAdd(hn::Set(d, vr[3 * i + 2]), g->mean[2], acc);
  }
  const M in_front = hn::Gt(g->p[2], hn::Set(d, kNearPlane));
  g->inv_z = hn::Div(hn::Set(d, 1.0f), g->p[2]);
  const V x_z = hn::Mul(g->p[0], g->inv_z);
  const V y_z = hn::Mul(g->p[1], g->inv_z);
  const V lim_x = hn::Set(d, job.lim_x), lim_y = hn::Set(d, job.lim_y);
  g->clamped_x = hn::Or(hn::Lt(x_z, hn::Neg(lim_x)), hn::Gt(x_z, lim_x));
  g->clamped_y = hn::Or(hn::Lt(y_z, hn::Neg(lim_y)), hn::Gt(y_z, lim_y));
  g->jx = hn::Min(hn::Max(x_z, hn::Neg(lim_x)), lim_x);
  g->jy = hn::Min(hn::Max(y_z, hn::Neg(lim_y)), lim_y);
  const V j00 = hn::Mul(hn::Set(d, job.fx), g->inv_z);
  const V j02 = hn::Mul(hn::Mul(hn::Set(d, -job.fx), g->jx), g->inv_z);
  const V j11 = hn::Mul(hn::Set(d, job.fy), g->inv_z);
  const V j12 = hn::Mul(hn::Mul(hn::Set(d, -job.fy), g->jy), g->inv_z);
  for (int j = 0; j < 3; ++j) {
    g->Mj[0][j] = hn::MulAdd(j00, hn::Set(d, vr[j]), hn::Mul(j02, hn::Set(d, vr[6 + j])));
    g->Mj[1][j] = hn::MulAdd(j11, hn::Set(d, vr[3 + j]), hn::Mul(j12, hn::Set(d, vr[6 + j])));
  }
  for (int k = 0; k < 2; ++k) {
    for (int i = 0; i < 3; ++i) {
      V acc = hn::Mul(g->cov[i][0], g->Mj[k][0]);
      acc = hn::MulAdd(g->cov[i][1], g->Mj[k][1], acc);
      g->u[k][i] = hn::MulAdd(g->cov[i][2], g->Mj[k][2], acc);
    }
  }
  const auto dot3 = [](const V* x, const V* y) {
    return hn::MulAdd(x[2], y[2], hn::MulAdd(x[1], y[1], hn::Mul(x[0], y[0])));
  };
  const V dilation = hn::Set(d, kCov2dDilation);
  g->a = hn::Add(dot3(g->Mj[0], g->u[0]), dilation);
  g->b = dot3(g->Mj[0], g->u[1]);
  g->c = hn::Add(dot3(g->Mj[1], g->u[1]), dilation);
  g->det = hn::Sub(hn::Mul(g->a, g->c), hn::Mul(g->b, g->b));
  const V mid = hn::Mul(hn::Set(d, 0.5f), hn::Add(g->a, g->c));
  g->lambda = hn::Add(mid, hn::Sqrt(hn::Max(hn::Set(d, 0.1f), hn::Sub(hn::Mul(mid, mid), g->det))));
  const M lambda_ok = hn::Gt(g->lambda, hn::Zero(d));
  const V r = hn::Ceil(hn::Mul(hn::Set(d, kRadiusSigmas), hn::Sqrt(g->lambda)));
  g->radius = hn::IfThenElseZero(lambda_ok, hn::Min(r, hn::Set(d, 1073741824.0f)));
  g->visible = hn::And(hn::And(in_front, hn::Gt(g->det, hn::Zero(d))),
                       hn::And(hn::Gt(g->marginal, hn::Set(d, kTemporalCullMarginal)),
                               hn::Gt(g->radius, hn::Zero(d))));
  g->radius = hn::IfThenElseZero(g->visible, g->radius);
}

HWY_INLINE V Sigmoid(V logit) {
  const D d;
  const V e = hn::Exp(d, hn::Min(hn::Max(hn::Neg(logit), hn::Set(d, -88.0f)), hn::Set(d, 88.0f)));
  return hn::Div(hn::Set(d, 1.0f), hn::Add(hn::Set(d, 1.0f), e));
}

// The colour-basis weights (sh4d.h EvalColorBasisWeights) of the lanes at `off`.
HWY_INLINE void ColorWeights(
    const PreprocessSimdJob& job, const BatchIn& in, int off, const Geometry& g, float* weights) {
  const D d;
  V dir[3];
  for (int i = 0; i < 3; ++i) dir[i] = hn::Sub(g.mean[i], hn::Set(d, job.center[i]));
  const V norm =
      hn::Sqrt(hn::MulAdd(dir[2], dir[2], hn::MulAdd(dir[1], dir[1], hn::Mul(dir[0], dir[0]))));
  const M positive = hn::Gt(norm, hn::Zero(d));
  const V x = hn::IfThenElseZero(positive, hn::Div(dir[0], norm));
  const V y = hn::IfThenElseZero(positive, hn::Div(dir[1], norm));
  const V z = hn::IfThenElseZero(positive, hn::Div(dir[2], norm));
  V w[16];
  const auto c = [&](double v) { return hn::Set(d, static_cast<float>(v)); };
  const int degree = job.sh_degree;
  w[0] = c(kShC0Double);
  if (degree >= 1) {
    w[1] = hn::Mul(c(-kShC1), y);
    w[2] = hn::Mul(c(kShC1), z);
    w[3] = hn::Mul(c(-kShC1), x);
  }
  if (degree >= 2) {
    const V xx = hn::Mul(x, x), yy = hn::Mul(y, y), zz = hn::Mul(z, z);
    const V xy = hn::Mul(x, y), yz = hn::Mul(y, z), xz = hn::Mul(x, z);
    w[4] = hn::Mul(c(kShC2[0]), xy);
    w[5] = hn::Mul(c(kShC2[1]), yz);
    w[6] = hn::Mul(c(kShC2[2]), hn::Sub(hn::Sub(hn::Add(zz, zz), xx), yy));
    w[7] = hn::Mul(c(kShC2[3]), xz);
    w[8] = hn::Mul(c(kShC2[4]), hn::Sub(xx, yy));
    if (degree >= 3) {
      const V three = c(3.0), four = c(4.0);
      const V t4 = hn::Sub(hn::Sub(hn::Mul(four, zz), xx), yy);
      w[9] = hn::Mul(hn::Mul(c(kShC3[0]), y), hn::Sub(hn::Mul(three, xx), yy));
      w[10] = hn::Mul(hn::Mul(c(kShC3[1]), xy), z);
      w[11] = hn::Mul(hn::Mul(c(kShC3[2]), y), t4);
      w[12] = hn::Mul(hn::Mul(c(kShC3[3]), z),
                      hn::Sub(hn::Sub(hn::Add(zz, zz), hn::Mul(three, xx)), hn::Mul(three, yy)));
      w[13] = hn::Mul(hn::Mul(c(kShC3[4]), x), t4);
      w[14] = hn::Mul(hn::Mul(c(kShC3[5]), z), hn::Sub(xx, yy));
      w[15] = hn::Mul(hn::Mul(c(kShC3[6]), x), hn::Sub(xx, hn::Mul(three, yy)));
    }
  }
  const int functions = job.functions;
  const int active = (degree + 1) * (degree + 1);
  // Up to the last coefficient the degrees use (the zeros between the time blocks' active
  // functions); nothing reads beyond it.
  for (int k = active; k < job.used_coefficients; ++k)
    hn::Store(hn::Zero(d), d, weights + k * kB + off);
  for (int lm = 0; lm < active; ++lm) hn::Store(w[lm], d, weights + lm * kB + off);
  if (job.time_degree == 0) return;
  // cos(n phase) by the Chebyshev recurrence, phase = 2 pi (mu_t - t) / T.
  const V dtc = hn::Sub(LoadRow(in.mean[3], off), hn::Set(d, job.time));
  const V c1 =
      hn::Cos(d, hn::Div(hn::Mul(c(2.0 * std::numbers::pi), dtc), hn::Set(d, job.duration)));
  V prev = hn::Set(d, 1.0f), cn = c1;
  for (int n = 1; n <= job.time_degree; ++n) {
    for (int lm = 0; lm < active; ++lm)
      hn::Store(hn::Mul(w[lm], cn), d, weights + (n * functions + lm) * kB + off);
    const V next = hn::Sub(hn::Mul(hn::Add(c1, c1), cn), prev);
    prev = cn;
    cn = next;
  }
}

void ForwardBatch(const PreprocessSimdJob& job,
                  const std::int64_t* index,
                  int count,
                  float* weights) {
  const D d;
  const DI di;
  const int lanes = static_cast<int>(hn::Lanes(d));
  BatchIn in;
  LoadBatch(job, index, count, &in);
  HWY_ALIGN float mx[kB], my[kB], ca[kB], cb[kB], cc[kB], depth[kB], opacity[kB];
  HWY_ALIGN std::int32_t screen[kB], bin[kB], reach_x[kB], reach_y[kB];
  for (int off = 0; off < count; off += lanes) {
    Geometry g;
    ComputeGeometry(job, in, off, &g);
    const V inv_z = g.inv_z;
    hn::Store(hn::MulAdd(hn::Mul(hn::Set(d, job.fx), g.p[0]), inv_z, hn::Set(d, job.cx)), d,
              mx + off);
    hn::Store(hn::MulAdd(hn::Mul(hn::Set(d, job.fy), g.p[1]), inv_z, hn::Set(d, job.cy)), d,
              my + off);
    const V inv_det = hn::Div(hn::Set(d, 1.0f), g.det);
    hn::Store(hn::Mul(g.c, inv_det), d, ca + off);
    hn::Store(hn::Mul(hn::Neg(g.b), inv_det), d, cb + off);
    hn::Store(hn::Mul(g.a, inv_det), d, cc + off);
    hn::Store(g.p[2], d, depth + off);
    const V o = hn::Mul(Sigmoid(LoadRow(in.logit, off)), g.marginal);
    hn::Store(o, d, opacity + off);
    hn::Store(hn::ConvertTo(di, g.radius), di, screen + off);
    // The binning radius (preprocess_common.h BinningRadius): where opacity x G reaches 1/255.
    const V reach = hn::Mul(o, hn::Set(d, 255.0f));
    const M reaches = hn::And(g.visible, hn::Gt(reach, hn::Set(d, 1.0f)));
    const V log_reach = hn::Log(d, hn::Max(reach, hn::Set(d, 1.0f)));
    const V rb =
        hn::Add(hn::Ceil(hn::Sqrt(hn::Mul(hn::Mul(hn::Set(d, 2.0f), log_reach), g.lambda))),
                hn::Set(d, 1.0f));
    const V bin_radius = hn::IfThenElseZero(reaches, hn::Min(rb, g.radius));
    hn::Store(hn::ConvertTo(di, bin_radius), di, bin + off);
    // Per axis (preprocess_common.h BinningReach): sqrt(2 ln(255 o) Sigma_xx), Sigma_yy.
    const V t2 = hn::Mul(hn::Set(d, 2.0f), log_reach);
    const auto axis = [&](V sigma) {
      const V r =
          hn::Add(hn::Ceil(hn::Sqrt(hn::Mul(t2, hn::Max(sigma, hn::Zero(d))))), hn::Set(d, 1.0f));
      return hn::ConvertTo(di, hn::Min(r, bin_radius));
    };
    hn::Store(axis(g.a), di, reach_x + off);
    hn::Store(axis(g.c), di, reach_y + off);
    if (!hn::AllFalse(d, g.visible)) ColorWeights(job, in, off, g, weights);
  }
  for (int l = 0; l < count; ++l) {
    const std::size_t i = static_cast<std::size_t>(index[l]);
    job.radius[i] = bin[l];
    job.reach[2 * i] = reach_x[l];
    job.reach[2 * i + 1] = reach_y[l];
    job.screen_radius[i] = screen[l];
    if (screen[l] == 0) continue;
    job.mean2d[2 * i] = mx[l];
    job.mean2d[2 * i + 1] = my[l];
    job.conic[3 * i] = ca[l];
    job.conic[3 * i + 1] = cb[l];
    job.conic[3 * i + 2] = cc[l];
    job.depth[i] = depth[l];
    job.opacity[i] = opacity[l];
  }
}

// Normalize's backward, (g - n (n.g)) / |q|, into out[m][off..]; zero where `keep` is false
// (culled lanes and the identity fallback).
HWY_INLINE void NormalizeBackward(const V* n, const V* gr, V norm, M keep, int off,
                                  float (*out)[kB]) {
  const D d;
  V ng = hn::Mul(n[0], gr[0]);
  for (int m = 1; m < 4; ++m) ng = hn::MulAdd(n[m], gr[m], ng);
  for (int m = 0; m < 4; ++m) {
    const V v = hn::Div(hn::NegMulAdd(n[m], ng, gr[m]), norm);
    hn::Store(hn::IfThenElseZero(keep, v), d, out[m] + off);
  }
}

// A kernel long on purpose: the chain's intermediate vectors (dmean, dcov, dSigma, dR) flow from
// stage to stage in registers within one function (opacity, projection, slice, covariance and
// rotation backward of a batch; BM_Preprocess), its stages marked by the comments below.
void BackwardBatch(const PreprocessSimdJob& job,
                   const std::int64_t* index,
                   int count,
                   float* weights) {
  const D d;
  const DI di;
  const int lanes = static_cast<int>(hn::Lanes(d));
  BatchIn in;
  LoadBatch(job, index, count, &in);
  HWY_ALIGN float g_m[2][kB], g_c[3][kB], g_o[kB];
  HWY_ALIGN std::int32_t radius[kB];
  std::memset(radius, 0, sizeof(radius));
  for (int l = 0; l < count; ++l) {
    const std::size_t i = static_cast<std::size_t>(index[l]);
    radius[l] = job.radius_in[i];
    const bool on = radius[l] > 0;
    for (int k = 0; k < 2; ++k) g_m[k][l] = on ? job.g_mean2d[2 * i + k] : 0.0f;
    for (int k = 0; k < 3; ++k) g_c[k][l] = on ? job.g_conic[3 * i + k] : 0.0f;
    g_o[l] = on ? job.g_opacity[i] : 0.0f;
  }
  HWY_ALIGN float out_mean[4][kB], out_scale[4][kB], out_ql[4][kB], out_qr[4][kB], out_logit[kB];
  for (int off = 0; off < count; off += lanes) {
    Geometry g;
    ComputeGeometry(job, in, off, &g);
    const M on = hn::RebindMask(d, hn::Gt(hn::Load(di, radius + off), hn::Zero(di)));
    const V gA = LoadRow(g_c[0], off), gB = LoadRow(g_c[1], off), gC = LoadRow(g_c[2], off);
    const V g_op = LoadRow(g_o, off);

    // Opacity = sigmoid(logit) x marginal.
    const V sig = Sigmoid(LoadRow(in.logit, off));
    const V one = hn::Set(d, 1.0f);
    const V d_logit = hn::Mul(hn::Mul(hn::Mul(g_op, g.marginal), sig), hn::Sub(one, sig));
    const V dmarginal = hn::Mul(g_op, sig);

    // ProjectEwaBackward.
    const V inv_z = g.inv_z, inv_z2 = hn::Mul(inv_z, inv_z);
    const V a = g.a, b = g.b, c = g.c, det = g.det;
    const V inv_det2 = hn::Div(one, hn::Mul(det, det));
    const V two = hn::Set(d, 2.0f);
    const V d_a =
        hn::Mul(hn::Sub(hn::Add(hn::Mul(hn::Neg(hn::Mul(c, c)), gA), hn::Mul(hn::Mul(b, c), gB)),
                        hn::Mul(hn::Mul(b, b), gC)),
                inv_det2);
    const V d_b = hn::Mul(hn::Add(hn::Sub(hn::Mul(hn::Mul(hn::Mul(two, b), c), gA),
                                          hn::Mul(hn::Add(det, hn::Mul(hn::Mul(two, b), b)), gB)),
                                  hn::Mul(hn::Mul(hn::Mul(two, a), b), gC)),
                          inv_det2);
    const V d_c =
        hn::Mul(hn::Sub(hn::Add(hn::Mul(hn::Neg(hn::Mul(b, b)), gA), hn::Mul(hn::Mul(a, b), gB)),
                        hn::Mul(hn::Mul(a, a), gC)),
                inv_det2);
    // dcov3 = M^T dC M with dC = [[d_a, d_b], [0, d_c]].
    V dcov[3][3];
    for (int i = 0; i < 3; ++i) {
      const V r0 = hn::Mul(g.Mj[0][i], d_a);
      const V r1 = hn::MulAdd(g.Mj[0][i], d_b, hn::Mul(g.Mj[1][i], d_c));
      for (int j = 0; j < 3; ++j) dcov[i][j] = hn::MulAdd(r0, g.Mj[0][j], hn::Mul(r1, g.Mj[1][j]));
    }
    // dM = dC P + dC^T P with P = M cov (rows u_k: cov is symmetric).
    V dM[2][3];
    for (int j = 0; j < 3; ++j) {
      dM[0][j] = hn::MulAdd(hn::Add(d_a, d_a), g.u[0][j], hn::Mul(d_b, g.u[1][j]));
      dM[1][j] = hn::MulAdd(d_b, g.u[0][j], hn::Mul(hn::Add(d_c, d_c), g.u[1][j]));
    }
    // dJ = dM R_view^T; only J's non-constant entries matter.
    const float* vr = job.rotation;
    const auto dj = [&](int k, int i) {
      return hn::MulAdd(dM[k][2], hn::Set(d, vr[3 * i + 2]),
                        hn::MulAdd(dM[k][1], hn::Set(d, vr[3 * i + 1]),
                                   hn::Mul(dM[k][0], hn::Set(d, vr[3 * i]))));
    };
    const V dj00 = dj(0, 0), dj11 = dj(1, 1), dj02 = dj(0, 2), dj12 = dj(1, 2);
    const V fx = hn::Set(d, job.fx), fy = hn::Set(d, job.fy);
    const V x = g.p[0], y = g.p[1];
    const V gm0 = LoadRow(g_m[0], off), gm1 = LoadRow(g_m[1], off);
    V dpz = hn::Neg(hn::MulAdd(hn::Mul(fx, inv_z2), dj00, hn::Mul(hn::Mul(fy, inv_z2), dj11)));
    // x: clamped, J(0,2) = -fx jx / z depends on z only; else -fx x / z^2.
    const V z_cx = hn::Mul(hn::Mul(hn::Mul(fx, g.jx), inv_z2), dj02);
    const V z_ux = hn::Mul(hn::Mul(hn::Mul(hn::Mul(two, fx), x), hn::Mul(inv_z2, inv_z)), dj02);
    dpz = hn::Add(dpz, hn::IfThenElse(g.clamped_x, z_cx, z_ux));
    V dpx = hn::IfThenElseZero(hn::Not(g.clamped_x), hn::Mul(hn::Neg(hn::Mul(fx, inv_z2)), dj02));
    const V z_cy = hn::Mul(hn::Mul(hn::Mul(fy, g.jy), inv_z2), dj12);
    const V z_uy = hn::Mul(hn::Mul(hn::Mul(hn::Mul(two, fy), y), hn::Mul(inv_z2, inv_z)), dj12);
    dpz = hn::Add(dpz, hn::IfThenElse(g.clamped_y, z_cy, z_uy));
    V dpy = hn::IfThenElseZero(hn::Not(g.clamped_y), hn::Mul(hn::Neg(hn::Mul(fy, inv_z2)), dj12));
    dpx = hn::MulAdd(hn::Mul(fx, inv_z), gm0, dpx);
    dpy = hn::MulAdd(hn::Mul(fy, inv_z), gm1, dpy);
    dpz = hn::NegMulAdd(hn::MulAdd(hn::Mul(fx, x), gm0, hn::Mul(hn::Mul(fy, y), gm1)), inv_z2, dpz);
    V dmean3[3];
    for (int i = 0; i < 3; ++i) {
      dmean3[i] =
          hn::MulAdd(hn::Set(d, vr[6 + i]), dpz,
                     hn::MulAdd(hn::Set(d, vr[3 + i]), dpy, hn::Mul(hn::Set(d, vr[i]), dpx)));
    }

    if (!job.temporal) {
      // Covariance3DBackward, then Rotation3DBackward (rotation4d.h), with G = dR.
      V dR[3][3], dlog3[3];
      for (int kk = 0; kk < 3; ++kk) {
        V diag = hn::Zero(d);
        for (int i = 0; i < 3; ++i) {
          V sr = hn::Mul(hn::Add(dcov[i][0], dcov[0][i]), g.R[0][kk]);
          for (int m = 1; m < 3; ++m)
            sr = hn::MulAdd(hn::Add(dcov[i][m], dcov[m][i]), g.R[m][kk], sr);
          dR[i][kk] = hn::Mul(sr, g.var[kk]);
          diag = hn::MulAdd(g.R[i][kk], sr, diag);
        }
        dlog3[kk] = hn::Mul(g.var[kk], diag);
      }
      const V w = g.ql[0], x = g.ql[1], y = g.ql[2], z = g.ql[3];
      const V x2 = hn::Add(x, x), y2 = hn::Add(y, y), z2 = hn::Add(z, z);
      // sum of p_k q_k minus sum of r_k s_k: one Rotation3DBackward row.
      const auto row = [](std::initializer_list<std::pair<V, V>> plus,
                          std::initializer_list<std::pair<V, V>> minus) {
        V acc = hn::Zero(D());
        for (const auto& [p, q] : plus) acc = hn::MulAdd(p, q, acc);
        for (const auto& [p, q] : minus) acc = hn::NegMulAdd(p, q, acc);
        return acc;
      };
      const V dq[4] = {
          hn::Mul(two, row({{y, dR[0][2]}, {z, dR[1][0]}, {x, dR[2][1]}},
                           {{z, dR[0][1]}, {x, dR[1][2]}, {y, dR[2][0]}})),
          hn::Mul(two, row({{y, dR[0][1]}, {z, dR[0][2]}, {y, dR[1][0]}, {z, dR[2][0]}, {w, dR[2][1]}},
                           {{x2, dR[1][1]}, {w, dR[1][2]}, {x2, dR[2][2]}})),
          hn::Mul(two, row({{x, dR[0][1]}, {w, dR[0][2]}, {x, dR[1][0]}, {z, dR[1][2]}, {z, dR[2][1]}},
                           {{y2, dR[0][0]}, {w, dR[2][0]}, {y2, dR[2][2]}})),
          hn::Mul(two, row({{x, dR[0][2]}, {w, dR[1][0]}, {y, dR[1][2]}, {x, dR[2][0]}, {y, dR[2][1]}},
                           {{z2, dR[0][0]}, {w, dR[0][1]}, {z2, dR[1][1]}}))};
      NormalizeBackward(g.ql, dq, g.ql_norm, hn::And(g.ql_ok, on), off, out_ql);
      for (int i = 0; i < 3; ++i) {
        hn::Store(hn::IfThenElseZero(on, dmean3[i]), d, out_mean[i] + off);
        hn::Store(hn::IfThenElseZero(on, dlog3[i]), d, out_scale[i] + off);
      }
      // No time axis: t, the 4th scale and q_r get no gradient.
      hn::Store(hn::Zero(d), d, out_mean[3] + off);
      hn::Store(hn::Zero(d), d, out_scale[3] + off);
      for (int k = 0; k < 4; ++k) hn::Store(hn::Zero(d), d, out_qr[k] + off);
      hn::Store(hn::IfThenElseZero(on, d_logit), d, out_logit + off);
      if (!hn::AllFalse(d, on)) ColorWeights(job, in, off, g, weights);
      continue;
    }

    // SliceAtTimeBackward.
    const V dt_inv = hn::Mul(g.dt, g.stt_inv);
    V k[3];
    for (int i = 0; i < 3; ++i) k[i] = hn::Mul(g.S[i][3], g.stt_inv);
    const V gm_dot_k =
        hn::MulAdd(dmean3[2], k[2], hn::MulAdd(dmean3[1], k[1], hn::Mul(dmean3[0], k[0])));
    const V marginal = g.marginal;
    const V dmu_t = hn::MulAdd(hn::Mul(dmarginal, marginal), dt_inv, hn::Neg(gm_dot_k));
    V col[3];  // dSigma(0..2, 3)
    for (int i = 0; i < 3; ++i) {
      V acc = hn::Mul(dmean3[i], dt_inv);
      for (int j = 0; j < 3; ++j) acc = hn::NegMulAdd(hn::Add(dcov[i][j], dcov[j][i]), k[j], acc);
      col[i] = acc;
    }
    V kGk = hn::Zero(d);
    for (int i = 0; i < 3; ++i) {
      V row = hn::Zero(d);
      for (int j = 0; j < 3; ++j) row = hn::MulAdd(dcov[i][j], k[j], row);
      kGk = hn::MulAdd(k[i], row, kGk);
    }
    V d_stt = hn::MulAdd(hn::Neg(gm_dot_k), dt_inv, kGk);
    d_stt = hn::Add(
        d_stt, hn::IfThenElseZero(hn::Gt(marginal, hn::Zero(d)),
                                  hn::Mul(hn::Mul(hn::Mul(dmarginal, marginal), hn::Set(d, 0.5f)),
                                          hn::Mul(dt_inv, dt_inv))));
    d_stt = hn::IfThenElseZero(hn::Not(g.floored), d_stt);

    // Covariance4DBackward: sym = dSigma + dSigma^T (dSigma(3, 0..2) = 0).
    V sym[4][4];
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) sym[i][j] = hn::Add(dcov[i][j], dcov[j][i]);
      sym[i][3] = sym[3][i] = col[i];
    }
    sym[3][3] = hn::Add(d_stt, d_stt);
    V dR[4][4], dlog[4];
    for (int kk = 0; kk < 4; ++kk) {
      V diag = hn::Zero(d);
      for (int i = 0; i < 4; ++i) {
        V sr = hn::Mul(sym[i][0], g.R[0][kk]);
        for (int m = 1; m < 4; ++m) sr = hn::MulAdd(sym[i][m], g.R[m][kk], sr);
        dR[i][kk] = hn::Mul(sr, g.var[kk]);
        diag = hn::MulAdd(g.R[i][kk], sr, diag);
      }
      dlog[kk] = hn::Mul(g.var[kk], diag);
    }

    // Rotation4DBackward: dA = dR reversed, G = dA M_r^T, H = M_l^T dA.
    V ml[4][4], mr[4][4];
    LeftIsoclinic(g.ql, ml);
    RightIsoclinic(g.qr, mr);
    V G[4][4], H[4][4];
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) {
        V gs = hn::Mul(dR[3 - i][3], mr[j][0]);
        V hs = hn::Mul(ml[0][i], dR[3][3 - j]);
        for (int m = 1; m < 4; ++m) {
          gs = hn::MulAdd(dR[3 - i][3 - m], mr[j][m], gs);
          hs = hn::MulAdd(ml[m][i], dR[3 - m][3 - j], hs);
        }
        G[i][j] = gs;
        H[i][j] = hs;
      }
    }
    const auto sum4 = [](V p, V q, V r, V s) { return hn::Add(hn::Add(hn::Add(p, q), r), s); };
    const V dl[4] = {sum4(G[0][0], G[1][1], G[2][2], G[3][3]),
                     sum4(hn::Neg(G[0][1]), G[1][0], hn::Neg(G[2][3]), G[3][2]),
                     sum4(hn::Neg(G[0][2]), G[1][3], G[2][0], hn::Neg(G[3][1])),
                     sum4(hn::Neg(G[0][3]), hn::Neg(G[1][2]), G[2][1], G[3][0])};
    const V dr[4] = {sum4(H[0][0], H[1][1], H[2][2], H[3][3]),
                     sum4(H[0][1], hn::Neg(H[1][0]), hn::Neg(H[2][3]), H[3][2]),
                     sum4(H[0][2], H[1][3], hn::Neg(H[2][0]), hn::Neg(H[3][1])),
                     sum4(H[0][3], hn::Neg(H[1][2]), H[2][1], hn::Neg(H[3][0]))};
    NormalizeBackward(g.ql, dl, g.ql_norm, hn::And(g.ql_ok, on), off, out_ql);
    NormalizeBackward(g.qr, dr, g.qr_norm, hn::And(g.qr_ok, on), off, out_qr);
    for (int i = 0; i < 3; ++i) hn::Store(hn::IfThenElseZero(on, dmean3[i]), d, out_mean[i] + off);
    hn::Store(hn::IfThenElseZero(on, dmu_t), d, out_mean[3] + off);
    for (int m = 0; m < 4; ++m) hn::Store(hn::IfThenElseZero(on, dlog[m]), d, out_scale[m] + off);
    hn::Store(hn::IfThenElseZero(on, d_logit), d, out_logit + off);
    if (!hn::AllFalse(d, on)) ColorWeights(job, in, off, g, weights);
  }
  for (int l = 0; l < count; ++l) {
    const std::size_t i = static_cast<std::size_t>(index[l]);
    for (int m = 0; m < 3; ++m) job.d_xyz[3 * i + m] = out_mean[m][l];
    job.d_t[i] = out_mean[3][l];
    for (int m = 0; m < 4; ++m) {
      job.d_log_scales[4 * i + m] = out_scale[m][l];
      job.d_rot_left[4 * i + m] = out_ql[m][l];
      job.d_rot_right[4 * i + m] = out_qr[m][l];
    }
    job.d_opacity_logit[i] = out_logit[l];
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace hdr4d::method::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hdr4d::method::detail {

HWY_EXPORT(TemporalSurvivors);
HWY_EXPORT(ForwardBatch);
HWY_EXPORT(BackwardBatch);

int PreprocessTemporalSurvivors(const PreprocessSimdJob& job,
                                std::int64_t begin,
                                int count,
                                std::int64_t* kept) {
  return HWY_DYNAMIC_DISPATCH(TemporalSurvivors)(job, begin, count, kept);
}

void PreprocessForwardSimd(const PreprocessSimdJob& job,
                           const std::int64_t* index,
                           int count,
                           float* weights) {
  HWY_DYNAMIC_DISPATCH(ForwardBatch)(job, index, count, weights);
}
void PreprocessBackwardSimd(const PreprocessSimdJob& job,
                            const std::int64_t* index,
                            int count,
                            float* weights) {
  HWY_DYNAMIC_DISPATCH(BackwardBatch)(job, index, count, weights);
}

}  // namespace hdr4d::method::detail
#endif  // HWY_ONCE
