// Speed of the image metrics at a typical test-view size (800x800 RGB, the HDR-4D-Syn
// resolution): windowed SSIM and PU21 PSNR (two pow() per value) are the expensive ones.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <random>

#include "core/image/image.h"
#include "core/metrics/metrics.h"

namespace hdr4d {
namespace {

Image Random(int width, int height, int channels, unsigned seed, float hi) {
  Image image(width, height, channels);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> dist(0.0f, hi);
  for (float& v : image.values()) v = dist(rng);
  return image;
}

constexpr int kSize = 800;

void BM_Ssim(benchmark::State& state) {
  const Image a = Random(kSize, kSize, 3, 1, 1.0f);
  const Image b = Random(kSize, kSize, 3, 2, 1.0f);
  for (auto _ : state) benchmark::DoNotOptimize(Ssim(a, b));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(a.size()));
}
BENCHMARK(BM_Ssim)->Unit(benchmark::kMillisecond);

void BM_Psnr(benchmark::State& state) {
  const Image a = Random(kSize, kSize, 3, 1, 1.0f);
  const Image b = Random(kSize, kSize, 3, 2, 1.0f);
  for (auto _ : state) benchmark::DoNotOptimize(Psnr(a, b));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(a.size()));
}
BENCHMARK(BM_Psnr)->Unit(benchmark::kMillisecond);

void BM_Pu21Psnr(benchmark::State& state) {
  const Image a = Random(kSize, kSize, 3, 3, 8.0f);
  const Image b = Random(kSize, kSize, 3, 4, 8.0f);
  for (auto _ : state) benchmark::DoNotOptimize(Pu21Psnr(a, b));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(a.size()));
}
BENCHMARK(BM_Pu21Psnr)->Unit(benchmark::kMillisecond);

void BM_HdrMetrics(benchmark::State& state) {
  const Image a = Random(kSize, kSize, 3, 5, 8.0f);
  const Image b = Random(kSize, kSize, 3, 6, 8.0f);
  for (auto _ : state) benchmark::DoNotOptimize(HdrMetrics(a, b));
}
BENCHMARK(BM_HdrMetrics)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace hdr4d
