// The appearance half of RayBatch (ray_batch.cpp): planes, basis matrix and MLP for the samples
// that pass the weight threshold, and every backward pass of a lane.
#include <algorithm>
#include <cmath>

#include "baselines/hexplane/dense_simd.h"
#include "baselines/hexplane/ray_batch_lane.h"
#include "baselines/hexplane/volume_render.h"
#include "baselines/sigmoid_tone_mapper.h"

namespace hdr4d::baselines::hexplane {

void RayBatch::Lane::Appearance(const HexPlaneModel& m, const std::vector<Ray>& rays, int explore,
                                float offset) {
  const HexPlaneConfig& c = m.config;
  const int P = 3 * c.app_comps, D = c.app_dim;
  const int num_rays = end - begin;
  app_sample.clear();
  app_first.assign(1, 0);
  for (int i = 0; i < num_rays; ++i) {
    const int n = first[i + 1] - first[i];
    const int stride = explore > 0 ? std::max(1, n / explore) : 0;
    const int phase = stride > 0 ? std::min(stride - 1, int(offset * stride)) : 0;
    for (int s = first[i]; s < first[i + 1]; ++s) {
      const bool explored = stride > 0 && (s - first[i]) % stride == phase;
      if (weight[s] > c.weight_threshold || explored) app_sample.push_back(s);
    }
    app_first.push_back(int(app_sample.size()));
  }
  const int M = int(app_sample.size());
  products.resize(M, P);
  std::vector<float> scratch(c.app_comps);
  for (int i = 0; i < num_rays; ++i)
    for (int r = app_first[i]; r < app_first[i + 1]; ++r)
      AppProducts(m.app, MakePointTaps(m.app, &xyz[3 * app_sample[r]], RayOf(rays, i).time),
                  products.row(r).data(), scratch.data());
  std::vector<float> basis_t(std::size_t(P) * D);  // P x D: the product's right operand
  for (int d = 0; d < D; ++d)
    for (int p = 0; p < P; ++p) basis_t[std::size_t(p) * D + d] = m.app_basis[std::size_t(d) * P + p];
  feat.resize(M, D);
  DenseProduct(M, D, P, products.data(), P, 1, basis_t.data(), D, feat.data(), D, false);
  const AppMlpShape shape = m.MlpShape();
  input.resize(M, shape.Inputs());
  for (int i = 0; i < num_rays; ++i)
    for (int r = app_first[i]; r < app_first[i + 1]; ++r)
      EncodeInput(shape, feat.row(r).data(), RayOf(rays, i).dir, input.row(r).data());
  AppMlpForward(shape.Layers(), m.mlp.data(), input, &acts);
  ToneMap(m, rays);
}

void RayBatch::Lane::ToneMap(const HexPlaneModel& m, const std::vector<Ray>& rays) {
  const int K = RayChannels(m), num_rays = end - begin;
  colour.assign(feature.size() * K, 0.0f);
  const RowMatrix<float>& y = acts.back();
  std::vector<float> ldr;
  for (int i = 0; i < num_rays; ++i) {
    const int a = app_first[i], n = app_first[i + 1] - a;
    if (K == 6 && n > 0) {
      const Ray& ray = RayOf(rays, i);
      ldr.resize(3 * n);
      SigmoidForward(m.OffsetOf(ray.image), ray.log_exposure, y.row(a).data(), n, ldr.data());
    }
    for (int r = a; r < a + n; ++r) {
      float* col = &colour[std::size_t(app_sample[r]) * K];
      for (int k = 0; k < 3; ++k) {
        if (K == 3) {
          col[k] = y(r, k);
        } else {
          col[k] = ldr[3 * (r - a) + k];
          col[3 + k] = std::exp(std::min(y(r, k), kMaxLogRadiance));
        }
      }
    }
  }
}

void RayBatch::Lane::Backward(const HexPlaneModel& m, const std::vector<Ray>& rays,
                              const float* dL_dout) {
  const HexPlaneConfig& c = m.config;
  const int K = RayChannels(m);
  std::vector<float> dcolour(colour.size()), dfeature(feature.size());
  std::vector<float> scratch(4 * c.density_comps);
  for (int i = 0; i < end - begin; ++i) {
    const int b = first[i], n = first[i + 1] - b;
    CompositeBackward(feature.data() + b, delta.data() + b, alpha.data() + b, weight.data() + b,
                      colour.data() + std::size_t(b) * K, n, K, c.density_shift,
                      background.data() + std::size_t(i) * K,
                      dL_dout + std::size_t(begin + i) * K, dcolour.data() + std::size_t(b) * K,
                      dfeature.data() + b);
    for (int s = b; s < b + n; ++s) {
      if (dfeature[s] == 0.0f) continue;
      DensityFeatureBackward(m.density, m.density_basis,
                             MakePointTaps(m.density, &xyz[3 * s], RayOf(rays, i).time),
                             dfeature[s], &grads->density, &grads->density_basis, scratch.data());
    }
  }
  BackgroundBackward(m, rays, dL_dout);
  AppearanceBackward(m, rays, dcolour);
}

void RayBatch::Lane::AppearanceBackward(const HexPlaneModel& m, const std::vector<Ray>& rays,
                                        const std::vector<float>& dcolour) {
  const HexPlaneConfig& c = m.config;
  const int K = RayChannels(m), P = 3 * c.app_comps, D = c.app_dim, M = int(app_sample.size());
  const RowMatrix<float>& y = acts.back();
  dout.resize(M, 3);
  std::vector<float> dldr, dlog;
  for (int i = 0; i < end - begin; ++i) {
    const int a = app_first[i], n = app_first[i + 1] - a;
    if (n == 0) continue;
    if (K == 3) {
      for (int r = a; r < a + n; ++r)
        for (int k = 0; k < 3; ++k) dout(r, k) = dcolour[std::size_t(app_sample[r]) * 3 + k];
      continue;
    }
    const Ray& ray = RayOf(rays, i);
    dldr.resize(3 * n);
    dlog.resize(3 * n);
    for (int r = a; r < a + n; ++r)
      for (int k = 0; k < 3; ++k) dldr[3 * (r - a) + k] = dcolour[std::size_t(app_sample[r]) * 6 + k];
    float doffset = 0;
    SigmoidBackward(m.OffsetOf(ray.image), ray.log_exposure, y.row(a).data(), n, dldr.data(),
                    dlog.data(), &doffset);
    if (ray.image >= 0 && ray.image < int(grads->exposure_offset.size()))
      grads->exposure_offset[ray.image] += doffset;
    for (int r = a; r < a + n; ++r)
      for (int k = 0; k < 3; ++k) {
        const float x = y(r, k);
        const float dhdr = dcolour[std::size_t(app_sample[r]) * 6 + 3 + k];
        dout(r, k) = dlog[3 * (r - a) + k] + (x < kMaxLogRadiance ? dhdr * std::exp(x) : 0.0f);
      }
  }
  const AppMlpShape shape = m.MlpShape();
  AppMlpBackward(shape.Layers(), m.mlp.data(), input, acts, dout, grads->mlp.data(), &din);
  RowMatrix<float> dfeat(M, D);
  for (int r = 0; r < M; ++r)
    EncodeInputBackward(shape, feat.row(r).data(), din.row(r).data(), dfeat.row(r).data());
  // dbasis += dfeat^T products (A(d, r) = dfeat(r, d)); dproducts = dfeat basis.
  DenseProduct(D, P, M, dfeat.data(), 1, D, products.data(), P, grads->app_basis.data(), P, true);
  RowMatrix<float> dproducts(M, P);
  DenseProduct(M, P, D, dfeat.data(), D, 1, m.app_basis.data(), P, dproducts.data(), P, false);
  std::vector<float> scratch(4 * c.app_comps);
  for (int i = 0; i < end - begin; ++i)
    for (int r = app_first[i]; r < app_first[i + 1]; ++r)
      AppProductsBackward(m.app, MakePointTaps(m.app, &xyz[3 * app_sample[r]], RayOf(rays, i).time),
                          dproducts.row(r).data(), &grads->app, scratch.data());
}

}  // namespace hdr4d::baselines::hexplane
