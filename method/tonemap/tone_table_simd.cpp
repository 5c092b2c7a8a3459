// Highway kernels of tone_table_simd.h, compiled for every x86 target Highway builds here.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "method/tonemap/tone_table_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
// Must come after foreach_target.h.
#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

#include <algorithm>

#include "method/tonemap/tone_table_simd.h"

HWY_BEFORE_NAMESPACE();
namespace hdr4d::method::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<float>;
using DI = hn::RebindToSigned<D>;
using V = hn::Vec<D>;
using VI = hn::Vec<DI>;

constexpr std::size_t kMaxLanes = HWY_MAX_BYTES / sizeof(float);

// One vector of values starting at a value of channel `phase`: what both kernels share.
struct Located {
  V y, w, slope;
  VI node;
  hn::Mask<D> inside;
};

struct Tables {
  const ToneTableView& t;
  V x_min, x_max, inv_step, log_e;
  VI last_interval;
  VI channel_base[3];  // per phase: ((phase + lane) % 3) * nodes

  explicit Tables(const ToneTableView& view) : t(view) {
    const D d;
    const DI di;
    x_min = hn::Set(d, view.x_min);
    x_max = hn::Set(d, view.x_max);
    inv_step = hn::Set(d, view.inv_step);
    log_e = hn::Set(d, view.log_exposure);
    last_interval = hn::Set(di, view.nodes - 2);
    HWY_ALIGN std::int32_t base[kMaxLanes];
    for (int phase = 0; phase < 3; ++phase) {
      for (std::size_t l = 0; l < hn::Lanes(di); ++l) {
        base[l] = std::int32_t((phase + l) % 3) * view.nodes;
      }
      channel_base[phase] = hn::Load(di, base);
    }
  }

  Located Locate(V log_hdr, int phase) const {
    const D d;
    const DI di;
    Located r;
    const V x = hn::Add(log_hdr, log_e);
    r.inside = hn::And(hn::Ge(x, x_min), hn::Le(x, x_max));  // false for NaN
    const V xc = hn::IfThenElse(r.inside, x, x_min);         // safe gathers for lanes outside
    const V u = hn::Mul(hn::Sub(xc, x_min), inv_step);
    const VI j = hn::Min(hn::ConvertTo(di, u), last_interval);  // u >= 0: truncation = floor
    r.w = hn::Sub(u, hn::ConvertTo(d, j));
    r.node = hn::Add(j, channel_base[phase]);
    const V z0 = hn::GatherIndex(d, t.z, r.node);
    r.slope = hn::GatherIndex(d, t.dz, r.node);
    const V z = hn::MulAdd(r.w, r.slope, z0);
    // Sigmoid without overflow: e = exp(-|z|), y = 1 / (1 + e) for z >= 0, else e / (1 + e).
    const V e = hn::Exp(d, hn::Neg(hn::Abs(z)));
    const V inv = hn::Div(hn::Set(d, 1.0f), hn::Add(hn::Set(d, 1.0f), e));
    r.y = hn::IfThenElse(hn::Ge(z, hn::Zero(d)), inv, hn::Mul(e, inv));
    return r;
  }
};

// Records the positions of lanes outside the table.
HWY_INLINE std::size_t RecordOutside(
    const Located& r, std::size_t v, std::size_t valid, std::int32_t* outside, std::size_t n_out) {
  const D d;
  if (hn::AllTrue(d, r.inside)) return n_out;
  HWY_ALIGN float in[kMaxLanes];
  hn::Store(hn::IfThenElseZero(r.inside, hn::Set(d, 1.0f)), d, in);
  for (std::size_t l = 0; l < valid; ++l) {
    if (in[l] == 0.0f) outside[n_out++] = std::int32_t(v + l);
  }
  return n_out;
}

// Calls body(v, valid, pointer offset) over full vectors, then once over a padded tail copy.
template <typename Body>
HWY_INLINE void ForEachVector(std::size_t count, const Body& body) {
  const D d;
  const std::size_t lanes = hn::Lanes(d);
  std::size_t v = 0;
  for (; v + lanes <= count; v += lanes) body(v, lanes);
  if (v < count) body(v, count - v);
}

std::size_t Forward(const ToneTableView& view,
                    const float* log_hdr,
                    std::size_t count,
                    float* ldr,
                    std::int32_t* outside) {
  const D d;
  const Tables tables(view);
  std::size_t n_out = 0;
  ForEachVector(count, [&](std::size_t v, std::size_t valid) {
    const int phase = int(v % 3);
    if (valid == hn::Lanes(d)) {
      const Located r = tables.Locate(hn::LoadU(d, log_hdr + v), phase);
      hn::StoreU(r.y, d, ldr + v);
      n_out = RecordOutside(r, v, valid, outside, n_out);
      return;
    }
    HWY_ALIGN float in[kMaxLanes] = {}, out[kMaxLanes];
    std::copy(log_hdr + v, log_hdr + v + valid, in);
    const Located r = tables.Locate(hn::Load(d, in), phase);
    hn::Store(r.y, d, out);
    std::copy(out, out + valid, ldr + v);
    n_out = RecordOutside(r, v, valid, outside, n_out);
  });
  return n_out;
}

std::size_t Backward(const ToneTableView& view,
                     const float* log_hdr,
                     const float* dL_dldr,
                     std::size_t count,
                     float* dL_dlog_hdr,
                     std::int32_t* node,
                     float* a0,
                     float* a1,
                     std::int32_t* outside) {
  const D d;
  const DI di;
  const Tables tables(view);
  const V one = hn::Set(d, 1.0f);
  std::size_t n_out = 0;
  auto step = [&](V lh, V g, int phase, V* dx, VI* nd, V* g0, V* g1) {
    const Located r = tables.Locate(lh, phase);
    const V dz = hn::IfThenElseZero(r.inside, hn::Mul(g, hn::Mul(r.y, hn::Sub(one, r.y))));
    *dx = hn::Mul(hn::Mul(dz, r.slope), tables.inv_step);
    *nd = r.node;
    *g1 = hn::Mul(dz, r.w);
    *g0 = hn::Sub(dz, *g1);
    return r;
  };
  ForEachVector(count, [&](std::size_t v, std::size_t valid) {
    const int phase = int(v % 3);
    V dx, g0, g1;
    VI nd;
    if (valid == hn::Lanes(d)) {
      const Located r =
          step(hn::LoadU(d, log_hdr + v), hn::LoadU(d, dL_dldr + v), phase, &dx, &nd, &g0, &g1);
      if (dL_dlog_hdr) hn::StoreU(dx, d, dL_dlog_hdr + v);
      hn::StoreU(nd, di, node + v);
      hn::StoreU(g0, d, a0 + v);
      hn::StoreU(g1, d, a1 + v);
      n_out = RecordOutside(r, v, valid, outside, n_out);
      return;
    }
    HWY_ALIGN float lh[kMaxLanes] = {}, g[kMaxLanes] = {}, o_dx[kMaxLanes], o_g0[kMaxLanes],
                    o_g1[kMaxLanes];
    HWY_ALIGN std::int32_t o_nd[kMaxLanes];
    std::copy(log_hdr + v, log_hdr + v + valid, lh);
    std::copy(dL_dldr + v, dL_dldr + v + valid, g);
    const Located r = step(hn::Load(d, lh), hn::Load(d, g), phase, &dx, &nd, &g0, &g1);
    hn::Store(dx, d, o_dx);
    hn::Store(nd, di, o_nd);
    hn::Store(g0, d, o_g0);
    hn::Store(g1, d, o_g1);
    if (dL_dlog_hdr) std::copy(o_dx, o_dx + valid, dL_dlog_hdr + v);
    std::copy(o_nd, o_nd + valid, node + v);
    std::copy(o_g0, o_g0 + valid, a0 + v);
    std::copy(o_g1, o_g1 + valid, a1 + v);
    n_out = RecordOutside(r, v, valid, outside, n_out);
  });
  return n_out;
}

}  // namespace HWY_NAMESPACE
}  // namespace hdr4d::method::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hdr4d::method::detail {

HWY_EXPORT(Forward);
HWY_EXPORT(Backward);

std::size_t ToneTableForward(const ToneTableView& table,
                             const float* log_hdr,
                             std::size_t count,
                             float* ldr,
                             std::int32_t* outside) {
  return HWY_DYNAMIC_DISPATCH(Forward)(table, log_hdr, count, ldr, outside);
}

std::size_t ToneTableBackward(const ToneTableView& table,
                              const float* log_hdr,
                              const float* dL_dldr,
                              std::size_t count,
                              float* dL_dlog_hdr,
                              std::int32_t* node,
                              float* a0,
                              float* a1,
                              std::int32_t* outside) {
  return HWY_DYNAMIC_DISPATCH(Backward)(table, log_hdr, dL_dldr, count, dL_dlog_hdr, node, a0, a1,
                                        outside);
}

}  // namespace hdr4d::method::detail
#endif  // HWY_ONCE
