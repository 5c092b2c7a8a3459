// Speed of the HexPlane engine's two hot spots (baselines/hexplane): the six-plane lookups of a
// sample (density feature; appearance products) with their scatter-add backward, and the
// appearance MLP over a batch of samples, forward and backward. The grid is the reference's
// first (64^3, 16 time cells, 24 density and 48 appearance components); the points are spread
// over the box, so the lookups miss the cache as a training batch's do.
// Args: points per iteration (lookups) or MLP rows; for the MLP, simd 0 runs the Eigen reference
// (BatchMlpForward/Backward, Eigen built for the baseline ISA) and 1 the training path
// (AppMlpForward/Backward on dense_simd.h, the target HDR4D_SIMD_TARGETS allows, named in the
// benchmark's label).
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "baselines/hexplane/app_mlp.h"
#include "baselines/hexplane/hex_field.h"
#include "method/raster/simd_dispatch.h"

namespace hdr4d::baselines::hexplane {
namespace {

struct Points {
  std::vector<float> xyz, t;
};

Points RandomPoints(int n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Points p;
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) p.xyz.push_back(u(rng));
    p.t.push_back(u(rng));
  }
  return p;
}

void BM_DensityLookup(benchmark::State& state) {
  const int n = int(state.range(0)), comps = 24;
  HexPlanes<float> planes(comps, {64, 64, 64}, 16), grads(comps, {64, 64, 64}, 16);
  InitPlanes(0.1f, 0.0f, 1, &planes);
  const std::vector<float> basis(3 * comps, 1.0f);
  std::vector<float> dbasis(3 * comps, 0.0f), scratch(4 * comps);
  const Points p = RandomPoints(n);
  const bool backward = state.range(1) != 0;
  for (auto _ : state) {
    float sum = 0;
    for (int i = 0; i < n; ++i) {
      const PointTaps<float> taps = MakePointTaps(planes, &p.xyz[3 * i], p.t[i]);
      sum += DensityFeature(planes, basis, taps, scratch.data());
      if (backward)
        DensityFeatureBackward(planes, basis, taps, 1e-3f, &grads, &dbasis, scratch.data());
    }
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_DensityLookup)->ArgsProduct({{4096}, {0, 1}})->ArgNames({"points", "backward"});

void BM_AppearanceLookup(benchmark::State& state) {
  const int n = int(state.range(0)), comps = 48;
  HexPlanes<float> planes(comps, {64, 64, 64}, 16), grads(comps, {64, 64, 64}, 16);
  InitPlanes(0.1f, 0.0f, 1, &planes);
  std::vector<float> out(3 * comps), dout(3 * comps, 1e-3f), scratch(4 * comps);
  const Points p = RandomPoints(n);
  const bool backward = state.range(1) != 0;
  for (auto _ : state) {
    for (int i = 0; i < n; ++i) {
      const PointTaps<float> taps = MakePointTaps(planes, &p.xyz[3 * i], p.t[i]);
      AppProducts(planes, taps, out.data(), scratch.data());
      if (backward) AppProductsBackward(planes, taps, dout.data(), &grads, scratch.data());
    }
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_AppearanceLookup)->ArgsProduct({{4096}, {0, 1}})->ArgNames({"points", "backward"});

// The reference's MLP: 27 features and the direction with 2 frequencies each (150 inputs), two
// hidden layers of 128, 3 outputs.
void BM_AppMlp(benchmark::State& state) {
  const int n = int(state.range(0));
  const AppMlpShape shape;
  const method::MlpShape layers = shape.Layers();
  const std::vector<float> params = InitAppMlp(shape, 3);
  std::vector<float> dparams(params.size(), 0.0f);
  std::mt19937 rng(5);
  std::normal_distribution<float> g(0.0f, 1.0f);
  RowMatrix<float> x(n, shape.Inputs()), dout(n, 3), dx;
  for (int i = 0; i < x.size(); ++i) x.data()[i] = g(rng);
  for (int i = 0; i < dout.size(); ++i) dout.data()[i] = 1e-3f * g(rng);
  std::vector<RowMatrix<float>> acts;
  const bool backward = state.range(1) != 0, simd = state.range(2) != 0;
  for (auto _ : state) {
    if (simd) {
      AppMlpForward(layers, params.data(), x, &acts);
      if (backward) AppMlpBackward(layers, params.data(), x, acts, dout, dparams.data(), &dx);
    } else {
      BatchMlpForward(layers, params.data(), x, &acts);
      if (backward) BatchMlpBackward(layers, params.data(), x, acts, dout, dparams.data(), &dx);
    }
    benchmark::DoNotOptimize(acts.back().data());
  }
  state.SetItemsProcessed(state.iterations() * n);
  state.SetLabel(simd ? method::ActiveSimdTarget() : "Eigen");
}
BENCHMARK(BM_AppMlp)
    ->ArgsProduct({{4096}, {0, 1}, {0, 1}})
    ->ArgNames({"rows", "backward", "simd"});

}  // namespace
}  // namespace hdr4d::baselines::hexplane
