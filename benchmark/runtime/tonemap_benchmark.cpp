// Speed of the Dynamic Tone Mapper for one view: BeginFrame (context learner + tables) + Map +
// MapBackward + EndFrameBackward, per Gaussian (3D branch: 20k and 100k Gaussians, 3 channels
// each) and per pixel of a 200x200 image (2D branch), tabulated (default) vs the direct MLP.
// Args: count (Gaussians, or image side for the image benchmark), tabulated (1/0).
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "method/tonemap/dynamic_tone_mapper.h"

namespace hdr4d::method {
namespace {

constexpr int kTimes = 30;

DynamicToneMapper MakeMapper(bool tabulated) {
  ToneMapperConfig config;
  config.num_times = kTimes;
  config.tabulated = tabulated;
  DynamicToneMapper mapper(config);
  std::mt19937 rng(1);
  std::normal_distribution<float> row(-1.0f, 0.3f);
  for (int t = 0; t < kTimes; ++t) {
    const float mean[3] = {row(rng), row(rng), row(rng)};
    mapper.ObserveMeanLogHdr(t, mean);
  }
  return mapper;
}

// Log-HDR colours of Gaussians (a few stops around 0.4 radiance) or of a raster, where empty
// background pixels sit at log(1e-5).
std::vector<float> LogHdr(std::size_t colours, bool image) {
  std::mt19937 rng(2);
  std::normal_distribution<float> lit(-1.0f, 1.5f);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> v(colours * 3);
  for (float& x : v) x = image && u(rng) < 0.3f ? std::log(1e-5f) : lit(rng);
  return v;
}

void RunFrames(benchmark::State& state, std::size_t colours, bool image) {
  const bool tabulated = state.range(1) != 0;
  DynamicToneMapper mapper = MakeMapper(tabulated);
  const std::vector<float> log_hdr = LogHdr(colours, image);
  std::vector<float> ldr(log_hdr.size()), dlog(log_hdr.size()), dL(log_hdr.size(), 1e-4f);
  const int side = static_cast<int>(state.range(0));
  int t = 0;
  for (auto _ : state) {
    mapper.BeginFrame({t, -1, std::log(2.0f)});
    if (image) {
      mapper.MapImage(log_hdr.data(), side, side, ldr.data());
      mapper.MapImageBackward(log_hdr.data(), side, side, dL.data(), dlog.data());
    } else {
      mapper.Map(log_hdr.data(), colours, ldr.data());
      mapper.MapBackward(log_hdr.data(), colours, dL.data(), dlog.data());
    }
    mapper.EndFrameBackward();
    t = (t + 1) % kTimes;
  }
  benchmark::DoNotOptimize(mapper.grads().data());
  state.counters["values/s"] =
      benchmark::Counter(double(colours) * 3 * state.iterations(), benchmark::Counter::kIsRate);
}

void BM_DtmGaussians(benchmark::State& state) {
  RunFrames(state, static_cast<std::size_t>(state.range(0)), false);
}
BENCHMARK(BM_DtmGaussians)
    ->Args({20000, 1})
    ->Args({100000, 1})
    ->Args({20000, 0})
    ->Args({100000, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_DtmImage(benchmark::State& state) {
  const std::size_t side = static_cast<std::size_t>(state.range(0));
  RunFrames(state, side * side, true);
}
BENCHMARK(BM_DtmImage)
    ->Args({200, 1})
    ->Args({200, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The per-view fixed cost alone: window, context learner, three tables.
void BM_DtmBeginFrame(benchmark::State& state) {
  DynamicToneMapper mapper = MakeMapper(state.range(1) != 0);
  int t = 0;
  for (auto _ : state) {
    mapper.BeginFrame({t, -1, 0.0f});
    t = (t + 1) % kTimes;
  }
}
BENCHMARK(BM_DtmBeginFrame)
    ->Args({0, 1})
    ->Args({0, 0})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

}  // namespace
}  // namespace hdr4d::method
