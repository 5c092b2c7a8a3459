// Speed of the core I/O and exposure work at the HDR-4D-Syn image size (800x800 RGB): EXR and
// PNG round trips, LDR synthesis with noise, the merge of a three-exposure bracket, and loading
// a real dataset's headers.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <random>

#include "core/crf.h"
#include "core/dataset.h"
#include "core/image_io.h"
#include "core/ldr_synthesis.h"

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
