// The reference preprocess (preprocess.h): per Gaussian, generic in T, every mode, straight from
// the header-only maths of method/gaussian/.
#include <vector>

#include "core/util/parallel.h"
#include "core/util/sigmoid.h"
#include "method/gaussian/projection.h"
#include "method/render/preprocess.h"
#include "method/render/preprocess_common.h"
#include "method/render/preprocess_reference_internal.h"

namespace hdr4d::method {
using namespace detail;

template <typename T>
void PreprocessForwardReference(const GaussianModelT<T>& model,
                                const ViewParams<T>& view,
                                T time,
                                const RenderOptions& options,
                                FrameStateT<T>* state) {
  BeginPreprocess(model, options, state);
  const std::size_t n = model.size();
  state->conditionals.resize(n);  // written for visible Gaussians only
  SplatBuffersT<T>& s = state->splats;
  const Vec3<T> center = view.Center();
  const int time_degree = TimeDegree(model, options);
  const std::size_t stride = model.rest_stride();
  const T duration = static_cast<T>(options.time_duration);
  std::vector<std::int64_t> visible_per_chunk((n + kGaussianGrain - 1) / kGaussianGrain, 0);
  ParallelForChunks(static_cast<std::int64_t>(n), kGaussianGrain,
                    [&](std::int64_t b, std::int64_t e) {
                      std::int64_t visible = 0;
                      for (std::int64_t g = b; g < e; ++g) {
                        const std::size_t i = static_cast<std::size_t>(g);
                        // The colour rows stream from memory (the optimiser's sweep evicts them):
                        // fetch a few Gaussians ahead.
                        if (stride > 0 && g + kColorAhead < e)
                          PrefetchRow(&model.color_rest[(i + kColorAhead) * stride], stride);
                        s.radius[i] = 0;
                        s.reach[2 * i] = s.reach[2 * i + 1] = 0;
                        const ConditionalGaussian<T> c = ConditionAt(model, i, time);
                        if (model.temporal && !TemporallyVisible(c.marginal))
                          continue;  // culled: costs nothing
                        const Splat2D<T> splat = ProjectEwa(c.mean, c.cov, view);
                        if (!splat.visible) continue;
                        s.mean2d[2 * i] = splat.mean.x();
                        s.mean2d[2 * i + 1] = splat.mean.y();
                        for (int k = 0; k < 3; ++k) s.conic[3 * i + k] = splat.conic[k];
                        s.depth[i] = splat.depth;
                        s.opacity[i] = Sigmoid(model.opacity_logit[i]) * c.marginal;
                        state->screen_radius[i] = splat.radius;
                        s.radius[i] = BinningRadius(splat, s.opacity[i]);
                        BinningReach(splat, s.opacity[i], s.radius[i], &s.reach[2 * i]);
                        state->conditionals[i] = c;  // the backward reuses it
                        // Colour is linear in the coefficients: weights . (DC, rest) + 0.5.
                        T w[kMaxColorCoefficients];
                        EvalColorBasisWeights(Vec3<T>(c.mean - center), model.t[i] - time, duration,
                                              model.basis, options.sh_degree, time_degree, w);
                        WriteColour(model, i, w, options, time_degree, state);
                        ++visible;
                      }
                      visible_per_chunk[b / kGaussianGrain] = visible;
                    });
  FinishPreprocess(options, model, visible_per_chunk, state);
}

namespace detail {

// Declared, with what it does, in preprocess_reference_internal.h.
template <typename T>
void GeometryBackward(const GaussianModelT<T>& model,
                      std::size_t i,
                      T time,
                      const ConditionalGaussian<T>& c,
                      const Vec3<T>& dmean3,
                      const Mat3<T>& dcov3,
                      T dmarginal,
                      GaussianGradientsT<T>* grads) {
  const Vec4<T> log_scales = Row4(model.log_scales, i);
  if (model.temporal) {
    Vec4<T> dmean4;
    Mat4<T> dsigma;
    SliceAtTimeBackward(Mean4(model, i), c.sigma4, time, dmean3, dcov3, dmarginal, &dmean4,
                        &dsigma);
    Mat4<T> drot;
    Vec4<T> dlog_scales;
    Covariance4DBackward(c.rotation4, log_scales, dsigma, &drot, &dlog_scales);
    Vec4<T> dql, dqr;
    Rotation4DBackward(Row4(model.rot_left, i), Row4(model.rot_right, i), drot, &dql, &dqr);
    for (int k = 0; k < 3; ++k) grads->xyz[i * 3 + k] += dmean4[k];
    grads->t[i] += dmean4[3];
    for (int k = 0; k < 4; ++k) {
      grads->log_scales[i * 4 + k] += dlog_scales[k];
      grads->rot_left[i * 4 + k] += dql[k];
      grads->rot_right[i * 4 + k] += dqr[k];
    }
    return;
  }
  Mat3<T> drot;
  Vec3<T> dlog_scales;
  Covariance3DBackward(c.rotation3, Vec3<T>(log_scales.template head<3>()), dcov3, &drot,
                       &dlog_scales);
  Vec4<T> dq;
  Rotation3DBackward(Row4(model.rot_left, i), drot, &dq);
  for (int k = 0; k < 3; ++k) {
    grads->xyz[i * 3 + k] += dmean3[k];
    grads->log_scales[i * 4 + k] += dlog_scales[k];
  }
  for (int k = 0; k < 4; ++k) grads->rot_left[i * 4 + k] += dq[k];
}

#define HDR4D_INSTANTIATE_GEOMETRY_BACKWARD(T)                                                 \
  template void GeometryBackward(const GaussianModelT<T>&, std::size_t, T,                    \
                                 const ConditionalGaussian<T>&, const Vec3<T>&, const Mat3<T>&, \
                                 T, GaussianGradientsT<T>*);
HDR4D_INSTANTIATE_GEOMETRY_BACKWARD(float)
HDR4D_INSTANTIATE_GEOMETRY_BACKWARD(double)
#undef HDR4D_INSTANTIATE_GEOMETRY_BACKWARD

}  // namespace detail

template <typename T>
void PreprocessBackwardReference(const GaussianModelT<T>& model,
                                 const ViewParams<T>& view,
                                 T time,
                                 const RenderOptions& options,
                                 const FrameStateT<T>& state,
                                 GaussianGradientsT<T>* grads,
                                 const GradientRowsDoneT<T>& rows_done) {
  const std::size_t n = model.size();
  HDR4D_CHECK(grads->size() == n && grads->color_rest.size() == model.color_rest.size());
  const int channels = model.channels;
  const SplatBuffersT<T>& s = state.splats;
  const SplatGradientsT<T>& sg = state.splat_grads;
  HDR4D_CHECK(sg.opacity.size() == n && state.conditionals.size() == n);
  const Vec3<T> center = view.Center();
  const int time_degree = TimeDegree(model, options);
  const std::size_t stride = model.rest_stride();
  const T duration = static_cast<T>(options.time_duration);
  ParallelFor(static_cast<std::int64_t>(n), kGaussianGrain, [&](std::int64_t g) {
    const std::size_t i = static_cast<std::size_t>(g);
    // Every row is written here (zeros for a culled Gaussian), so the caller needs no separate
    // pass that clears 160 floats per Gaussian before each backward.
    const bool visible = s.radius[i] > 0;
    ZeroRows(grads, i, !visible);
    if (!visible) return;
    const ConditionalGaussian<T>& c = state.conditionals[i];

    T w[kMaxColorCoefficients];
    EvalColorBasisWeights(Vec3<T>(c.mean - center), model.t[i] - time, duration, model.basis,
                          options.sh_degree, time_degree, w);
    WriteColourGradient(model, i, w, options, state, model.basis.coefficients(),
                        &grads->color_dc[i * channels], &grads->color_rest[i * stride]);

    // Opacity = sigmoid(logit) x marginal.
    const T sig = Sigmoid(model.opacity_logit[i]);
    grads->opacity_logit[i] += sg.opacity[i] * c.marginal * sig * (T(1) - sig);
    const T dmarginal = sg.opacity[i] * sig;

    Vec3<T> dmean3;
    Mat3<T> dcov3;
    ProjectEwaBackward(c.mean, c.cov, view, Vec2<T>(sg.mean2d[2 * i], sg.mean2d[2 * i + 1]),
                       Vec3<T>(sg.conic[3 * i], sg.conic[3 * i + 1], sg.conic[3 * i + 2]), &dmean3,
                       &dcov3);
    GeometryBackward(model, i, time, c, dmean3, dcov3, dmarginal, grads);
  });
  if (!rows_done) return;
  ParallelForChunks(
      static_cast<std::int64_t>(n), kGaussianGrain, [&](std::int64_t b, std::int64_t e) {
        const std::size_t i = static_cast<std::size_t>(b);
        rows_done(b, e,
                  GradientRowsT<T>{&grads->color_dc[i * channels], &grads->color_rest[i * stride]});
      });
}

#define HDR4D_INSTANTIATE_PREPROCESS_REFERENCE(T)                                              \
  template void PreprocessForwardReference(const GaussianModelT<T>&, const ViewParams<T>&, T,  \
                                           const RenderOptions&, FrameStateT<T>*);             \
  template void PreprocessBackwardReference(const GaussianModelT<T>&, const ViewParams<T>&, T, \
                                            const RenderOptions&, const FrameStateT<T>&,       \
                                            GaussianGradientsT<T>*, const GradientRowsDoneT<T>&);
HDR4D_INSTANTIATE_PREPROCESS_REFERENCE(float)
HDR4D_INSTANTIATE_PREPROCESS_REFERENCE(double)
#undef HDR4D_INSTANTIATE_PREPROCESS_REFERENCE

}  // namespace hdr4d::method
