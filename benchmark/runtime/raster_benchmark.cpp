// Speed of the CPU tile rasteriser (method/raster): binning, the blend forward and its backward,
// both backends, at 200x200, 400x400 and 800x800 with 20k and 100k random splats.
//
// Scene: means uniform over the image (plus a margin), anisotropic covariances with the 0.3
// dilation, opacity uniform in [0.05, 0.6], 3-channel features (6 with the "/6ch" runs). The
// Gaussians' screen size scales with the image width and with 1/sqrt(count), so every
// configuration has the same depth complexity: about 35 contributing Gaussians per pixel (the
// target for 200x200 with 20k; counter `contrib/px` reports the measured mean).
// Counters: `Mblend/s` = contributing (pixel, Gaussian) blends per second; `Mpair/s` = pairs the
// kernel walks through (sum of n_contrib: every listed Gaussian up to the last contributor);
// `threads` = the ThreadLimit used (1 gives per-thread speed).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <random>
#include <tuple>
#include <vector>

#include "core/util/parallel.h"
#include "method/gaussian/constants.h"
#include "method/raster/binning.h"
#include "method/raster/blend.h"

namespace hdr4d::method {
namespace {

// Screen sigma (pixels) at 200 px width and 20k Gaussians; tuned for ~35 contributors/pixel.
constexpr double kBaseSigma = 1.6;

struct Scene {
  SplatBuffers splats;
  RasterSettings settings;
  double contributors_per_pixel = 0;  // mean number of Gaussians blended into a pixel
  double pairs_per_pixel = 0;         // mean n_contrib
  std::vector<float> dL_dimage;
};

SplatBuffers MakeSplats(int size, int count, int channels, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double sigma = kBaseSigma * (size / 200.0) * std::sqrt(20000.0 / count);
  const double margin = 3 * sigma;
  SplatBuffers s;
  s.channels = channels;
  s.Resize(count);
  for (int g = 0; g < count; ++g) {
    s.mean2d[2 * g] = static_cast<float>(-margin + (size + 2 * margin) * u(rng));
    s.mean2d[2 * g + 1] = static_cast<float>(-margin + (size + 2 * margin) * u(rng));
    const double s1 = sigma * (0.5 + u(rng)), s2 = sigma * (0.5 + u(rng));
    const double th = 3.14159265358979 * u(rng);
    const double c = std::cos(th), sn = std::sin(th);
    const double xx = c * c * s1 * s1 + sn * sn * s2 * s2 + kCov2dDilation;
    const double yy = sn * sn * s1 * s1 + c * c * s2 * s2 + kCov2dDilation;
    const double xy = c * sn * (s1 * s1 - s2 * s2);
    const double det = xx * yy - xy * xy;
    s.conic[3 * g] = static_cast<float>(yy / det);
    s.conic[3 * g + 1] = static_cast<float>(-xy / det);
    s.conic[3 * g + 2] = static_cast<float>(xx / det);
    const double mid = 0.5 * (xx + yy);
    const double lambda_max = mid + std::sqrt(std::max(0.1, mid * mid - det));
    s.opacity[g] = static_cast<float>(0.05 + 0.55 * u(rng));
    // As the preprocess bins them (preprocess_common.h BinningRadius, BinningReach): the 3-sigma
    // radius cut to where alpha reaches 1/255, and that reach per axis.
    const double t2 = 2.0 * std::log(255.0 * s.opacity[g]);
    const auto reach = [&](double variance) {
      return static_cast<int>(std::ceil(std::sqrt(t2 * variance))) + 1;
    };
    s.radius[g] = std::min(static_cast<int>(std::ceil(kRadiusSigmas * std::sqrt(lambda_max))),
                           reach(lambda_max));
    s.reach.push_back(std::min(s.radius[g], reach(xx)));
    s.reach.push_back(std::min(s.radius[g], reach(yy)));
    s.depth[g] = static_cast<float>(1.0 + 10.0 * u(rng));
    for (int ch = 0; ch < channels; ++ch)
      s.features[g * channels + ch] = static_cast<float>(u(rng));
  }
  return s;
}

// Counts the blends of a rendered frame with the reference rules.
void CountBlends(Scene* scene, const RasterState& state) {
  const SplatBuffers& s = scene->splats;
  double blends = 0, pairs = 0;
  for (int y = 0; y < state.height; ++y) {
    for (int x = 0; x < state.width; ++x) {
      const int tile = (y / kTileSize) * state.tiles_x + x / kTileSize;
      const int n = state.n_contrib[static_cast<std::size_t>(y) * state.width + x];
      pairs += n;
      for (int k = 0; k < n; ++k) {
        const int g = state.point_list[state.tile_ranges[tile] + k];
        const float dx = s.mean2d[2 * g] - (x + 0.5f), dy = s.mean2d[2 * g + 1] - (y + 0.5f);
        const float power = -0.5f * (s.conic[3 * g] * dx * dx + s.conic[3 * g + 2] * dy * dy) -
                            s.conic[3 * g + 1] * dx * dy;
        if (power > 0) continue;
        const float alpha = std::min(kMaxAlpha, s.opacity[g] * std::exp(power));
        blends += alpha >= kMinAlpha;
      }
    }
  }
  const double pixels = static_cast<double>(state.width) * state.height;
  scene->contributors_per_pixel = blends / pixels;
  scene->pairs_per_pixel = pairs / pixels;
}

const Scene& GetScene(int size, int count, int channels) {
  static std::map<std::tuple<int, int, int>, std::unique_ptr<Scene>> cache;
  auto& slot = cache[{size, count, channels}];
  if (!slot) {
    slot = std::make_unique<Scene>();
    slot->splats = MakeSplats(size, count, channels, 1234u + size + count);
    slot->settings.width = size;
    slot->settings.height = size;
    slot->settings.background.assign(channels, 0.0f);
    std::vector<float> image(static_cast<std::size_t>(size) * size * channels);
    RasterState state;
    RasterizeForward(slot->splats, slot->settings, &state, image.data());
    CountBlends(slot.get(), state);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    slot->dL_dimage.resize(image.size());
    for (float& v : slot->dL_dimage) v = u(rng);
  }
  return *slot;
}

// Args: image size, Gaussian count, threads, backend (0 scalar, 1 simd), channels.
struct Config {
  int size, count, threads, channels;
  RasterBackend backend;
};
Config ConfigOf(const benchmark::State& state) {
  return {static_cast<int>(state.range(0)), static_cast<int>(state.range(1)),
          static_cast<int>(state.range(2)), static_cast<int>(state.range(4)),
          state.range(3) == 0 ? RasterBackend::kScalar : RasterBackend::kSimd};
}

void SetCounters(benchmark::State& state, const Scene& scene, int threads) {
  const double pixels = static_cast<double>(scene.settings.width) * scene.settings.height;
  state.counters["contrib/px"] = scene.contributors_per_pixel;
  state.counters["Mblend/s"] = benchmark::Counter(scene.contributors_per_pixel * pixels / 1e6,
                                                  benchmark::Counter::kIsIterationInvariantRate);
  state.counters["Mpair/s"] = benchmark::Counter(scene.pairs_per_pixel * pixels / 1e6,
                                                 benchmark::Counter::kIsIterationInvariantRate);
  state.counters["threads"] = threads;
}

void BM_RasterForward(benchmark::State& state) {
  const Config c = ConfigOf(state);
  ThreadLimit limit(c.threads);
  const Scene& scene = GetScene(c.size, c.count, c.channels);
  RasterSettings settings = scene.settings;
  settings.backend = c.backend;
  RasterState raster;
  BinSplats(scene.splats, settings, &raster);
  std::vector<float> image(static_cast<std::size_t>(c.size) * c.size * c.channels);
  for (auto _ : state) {
    BlendForward(scene.splats, settings, &raster, image.data());
    benchmark::DoNotOptimize(image.data());
  }
  SetCounters(state, scene, c.threads);
}

// What the backward keeps per Gaussian beside its gradients (train --prune-contribution).
enum class Tracked { kNothing, kWeights, kShares };

// The blend's backward on one scene; with `split`, with a separate geometry image as
// train --no-hdr-geometry passes (BlendBackward), to time the split against the plain backward;
// with `tracked`, keeping the largest weights or radiance shares (--prune-radiance-share).
void BenchBlendGradients(benchmark::State& state, bool split,
                         Tracked tracked = Tracked::kNothing) {
  const Config c = ConfigOf(state);
  ThreadLimit limit(c.threads);
  const Scene& scene = GetScene(c.size, c.count, c.channels);
  RasterSettings settings = scene.settings;
  settings.backend = c.backend;
  RasterState raster;
  std::vector<float> image(static_cast<std::size_t>(c.size) * c.size * c.channels);
  RasterizeForward(scene.splats, settings, &raster, image.data());
  std::vector<float> geometry;
  if (split) {
    geometry = scene.dL_dimage;
    for (float& v : geometry) v *= 0.5f;
  }
  if (tracked == Tracked::kShares) settings.share_image = image.data();
  SplatGradients grads;
  std::vector<float> dbg(c.channels);
  for (auto _ : state) {
    grads.SetZero(scene.splats.size(), c.channels);
    if (tracked != Tracked::kNothing) grads.max_weight.assign(scene.splats.size(), 0.0f);
    BlendBackward(scene.splats, settings, &raster, scene.dL_dimage.data(), nullptr, &grads,
                  dbg.data(), split ? geometry.data() : nullptr);
    benchmark::DoNotOptimize(grads.opacity.data());
  }
  SetCounters(state, scene, c.threads);
}

void BM_RasterBackward(benchmark::State& state) { BenchBlendGradients(state, false); }

// Range argument 5: 0 without the geometry image, 1 with it (the same 6-channel scene).
void BM_RasterBackwardGeometry(benchmark::State& state) {
  BenchBlendGradients(state, state.range(5) != 0);
}

// Range argument 5: 0 plain, 1 keeping the largest weights, 2 the largest radiance shares.
void BM_RasterBackwardTracked(benchmark::State& state) {
  BenchBlendGradients(state, false, static_cast<Tracked>(state.range(5)));
}

// What one training iteration asks of the rasteriser: bin, blend, back-propagate.
void BM_RasterTrainStep(benchmark::State& state) {
  const Config c = ConfigOf(state);
  ThreadLimit limit(c.threads);
  const Scene& scene = GetScene(c.size, c.count, c.channels);
  RasterSettings settings = scene.settings;
  settings.backend = c.backend;
  RasterState raster;
  std::vector<float> image(static_cast<std::size_t>(c.size) * c.size * c.channels);
  SplatGradients grads;
  for (auto _ : state) {
    RasterizeForward(scene.splats, settings, &raster, image.data());
    grads.SetZero(scene.splats.size(), c.channels);
    BlendBackward(scene.splats, settings, &raster, scene.dL_dimage.data(), nullptr, &grads,
                  nullptr);
    benchmark::DoNotOptimize(grads.opacity.data());
  }
  SetCounters(state, scene, c.threads);
}

void BM_RasterBinning(benchmark::State& state) {
  const Config c = ConfigOf(state);
  ThreadLimit limit(c.threads);
  const Scene& scene = GetScene(c.size, c.count, c.channels);
  RasterState raster;
  for (auto _ : state) {
    BinSplats(scene.splats, scene.settings, &raster);
    benchmark::DoNotOptimize(raster.point_list.data());
  }
  state.counters["entries"] = static_cast<double>(raster.num_entries());
  state.counters["threads"] = c.threads;
}

void BlendArgs(benchmark::internal::Benchmark* b) {
  for (int backend : {1, 0})
    for (int size : {200, 400, 800})
      for (int count : {20000, 100000})
        for (int threads : {1, 2}) b->Args({size, count, threads, backend, 3});
  for (int threads : {1, 2}) b->Args({200, 20000, threads, 1, 6});
  b->Unit(benchmark::kMillisecond)->UseRealTime();
}

void BinningArgs(benchmark::internal::Benchmark* b) {
  for (int size : {200, 400, 800})
    for (int count : {20000, 100000})
      for (int threads : {1, 2}) b->Args({size, count, threads, 1, 3});
  b->Unit(benchmark::kMillisecond)->UseRealTime();
}

void TrainStepArgs(benchmark::internal::Benchmark* b) {
  for (int channels : {3, 6})
    for (int threads : {1, 2}) b->Args({200, 20000, threads, 1, channels});
  b->Unit(benchmark::kMillisecond)->UseRealTime();
}

BENCHMARK(BM_RasterForward)->Apply(BlendArgs);
BENCHMARK(BM_RasterBackward)->Apply(BlendArgs);
BENCHMARK(BM_RasterBinning)->Apply(BinningArgs);
BENCHMARK(BM_RasterTrainStep)->Apply(TrainStepArgs);
BENCHMARK(BM_RasterBackwardGeometry)->Apply([](benchmark::internal::Benchmark* b) {
  for (int size : {200, 400})
    for (int split : {0, 1}) b->Args({size, 20000, 2, 1, 6, split});
  b->Unit(benchmark::kMillisecond)->UseRealTime();
});

BENCHMARK(BM_RasterBackwardTracked)->Apply([](benchmark::internal::Benchmark* b) {
  for (int tracked : {0, 1, 2}) b->Args({200, 20000, 1, 1, 6, tracked});
  b->Unit(benchmark::kMillisecond)->UseRealTime();
});

}  // namespace
}  // namespace hdr4d::method
