// Speed of the core I/O and exposure work at the HDR-4D-Syn image size (800x800 RGB): EXR and
// PNG round trips, LDR synthesis with noise, the merge of a three-exposure bracket, and loading
// a real dataset's headers.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "core/radiometry/crf.h"
#include "core/dataset/dataset.h"
#include "core/image/image_io.h"
#include "core/radiometry/ldr_synthesis.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;

constexpr int kSize = 800;

Image RandomHdr(unsigned seed) {
  Image image(kSize, kSize, 3);
  std::mt19937 rng(seed);
  std::lognormal_distribution<float> dist(0.0f, 2.0f);  // radiance over several decades
  for (float& v : image.values()) v = dist(rng);
  return image;
}

fs::path ScratchDir() {
  const fs::path dir = fs::temp_directory_path() / ("hdr4d_bench_" + std::to_string(getpid()));
  fs::create_directories(dir);
  return dir;
}

void BM_WriteExrHalf(benchmark::State& state) {
  const Image hdr = RandomHdr(1);
  const fs::path path = ScratchDir() / "w.exr";
  for (auto _ : state) WriteImage(path, hdr);
  fs::remove_all(path.parent_path());
}
BENCHMARK(BM_WriteExrHalf)->Unit(benchmark::kMillisecond);

void BM_ReadExrHalf(benchmark::State& state) {
  const fs::path path = ScratchDir() / "r.exr";
  WriteImage(path, RandomHdr(2));
  for (auto _ : state) benchmark::DoNotOptimize(ReadImage(path));
  fs::remove_all(path.parent_path());
}
BENCHMARK(BM_ReadExrHalf)->Unit(benchmark::kMillisecond);

void BM_ReadPng8(benchmark::State& state) {
  const fs::path path = ScratchDir() / "r.png";
  WriteImage(path, SynthesizeLdr(RandomHdr(3), *ParseCrf("srgb"), {.exposure = 0.5}));
  for (auto _ : state) benchmark::DoNotOptimize(ReadImage(path));
  fs::remove_all(path.parent_path());
}
BENCHMARK(BM_ReadPng8)->Unit(benchmark::kMillisecond);

// An 8-bit PNG of smooth content, as a render is (noise would be incompressible at any level),
// at zlib level state.range(0) (-1: libpng's default, 6); the file size is a counter.
void BM_WritePng8(benchmark::State& state) {
  Image hdr(kSize, kSize, 3);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x)
      for (int c = 0; c < 3; ++c)
        hdr.at(x, y, c) = std::exp(2.0f * std::sin(0.013f * x + c) * std::cos(0.021f * y) +
                                   0.5f * std::sin(0.1f * (x + y)));
  const Image ldr = SynthesizeLdr(hdr, *ParseCrf("srgb"), {.exposure = 0.5});
  const fs::path path = ScratchDir() / "w.png";
  const ImageWriteOptions options{.png_compression = static_cast<int>(state.range(0))};
  for (auto _ : state) WriteImage(path, ldr, options);
  state.counters["bytes"] = static_cast<double>(fs::file_size(path));
  fs::remove_all(path.parent_path());
}
BENCHMARK(BM_WritePng8)->Arg(-1)->Arg(3)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_SynthesizeLdrWithNoise(benchmark::State& state) {
  const Image hdr = RandomHdr(4);
  const auto crf = ParseCrf("filmic");
  LdrSynthesisOptions options{.exposure = 2.0,
                              .noise = {.full_well = 20000, .read_sigma = 0.002, .seed = 1}};
  for (auto _ : state) benchmark::DoNotOptimize(SynthesizeLdr(hdr, *crf, options));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(hdr.size()));
}
BENCHMARK(BM_SynthesizeLdrWithNoise)->Unit(benchmark::kMillisecond);

void BM_MergeThreeExposures(benchmark::State& state) {
  const Image hdr = RandomHdr(5);
  const auto crf = ParseCrf("filmic");
  const std::vector<double> exposures = {0.125, 2.0, 32.0};
  std::vector<Image> stack;
  for (double e : exposures) stack.push_back(SynthesizeLdr(hdr, *crf, {.exposure = e}));
  for (auto _ : state) benchmark::DoNotOptimize(MergeExposures(stack, exposures, *crf));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(hdr.size()));
}
BENCHMARK(BM_MergeThreeExposures)->Unit(benchmark::kMillisecond);

// The real D-NeRF lego scene (81 frames, 100x100) when ../shared/data is next to the checkout.
void BM_LoadLegoHeaders(benchmark::State& state) {
  const fs::path root = fs::path(HDR4D_SOURCE_DIR) / ".." / "shared" / "data" / "dnerf_lego_tiny";
  if (!fs::exists(root)) {
    state.SkipWithError("../shared/data/dnerf_lego_tiny not found");
    return;
  }
  for (auto _ : state)
    benchmark::DoNotOptimize(LoadDataset(root, {.image_check = ImageCheck::kHeaders}));
}
BENCHMARK(BM_LoadLegoHeaders)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace hdr4d
