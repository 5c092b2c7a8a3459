// Speed of the image metrics at a typical test-view size (800x800 RGB, the HDR-4D-Syn
// resolution): windowed SSIM and PU21 PSNR (two pow() per value) are the expensive ones; FLIP
// (core/metrics/flip.h) filters six planes per image, HDR-FLIP once per exposure.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <random>

#include "core/image/image.h"
#include "core/metrics/flip.h"
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

void BM_Flip(benchmark::State& state) {
  Image a = Random(kSize, kSize, 3, 7, 1.0f), b = Random(kSize, kSize, 3, 8, 1.0f);
  a.set_encoding(Encoding::kSrgb), b.set_encoding(Encoding::kSrgb);
  for (auto _ : state) benchmark::DoNotOptimize(Flip(a, b));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(a.num_pixels()));
}
BENCHMARK(BM_Flip)->Unit(benchmark::kMillisecond);

// Radiance over 12 stops (e^-4 .. e^8): the reference's exposure range gives 9 exposures.
void BM_HdrFlip(benchmark::State& state) {
  Image a = Random(kSize, kSize, 3, 9, 12.0f), b = Random(kSize, kSize, 3, 10, 12.0f);
  for (Image* image : {&a, &b}) {
    for (float& v : image->values()) v = std::exp(v - 4.0f);
  }
  state.counters["exposures"] = HdrFlipExposureRange(a).count;
  for (auto _ : state) benchmark::DoNotOptimize(HdrFlip(b, a));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(a.num_pixels()));
}
BENCHMARK(BM_HdrFlip)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace hdr4d
