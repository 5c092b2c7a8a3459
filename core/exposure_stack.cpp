#include "core/exposure_stack.h"

#include <cmath>

#include <fmt/format.h>

#include <map>
#include <set>
#include <vector>

#include "core/dataset.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_util.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

constexpr const char* kManifestName = "synthesis.json";

// SplitMix64 finaliser: decorrelates per-frame seeds derived from one user seed.
std::uint64_t MixSeed(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

std::vector<const Frame*> FramesOfSplit(const Dataset& dataset, const std::string& split) {
  std::vector<const Frame*> frames;
  for (const Frame* f : dataset.AllFrames()) {
    if (split == "all" || split == SplitName(f->split)) frames.push_back(f);
  }
  return frames;
}

}  // namespace

void DatasetSynthesisOptions::Validate() const {
  ParseCrf(crf);  // throws with a clear message for a bad spec
  LdrSynthesisOptions probe;
  probe.noise = noise;
  probe.bits = bits;
  probe.Validate();
  if (bits == 0) Fail("synth-ldr: a dataset's LDR images are integer PNGs; use 8 or 16 bits");
  if (!std::isfinite(gain_drift) || std::abs(gain_drift) > 20)
    Fail("synth-ldr: gain drift {} must be finite and within [-20, 20]", gain_drift);
}

int SynthesizeDatasetLdr(const fs::path& root, const DatasetSynthesisOptions& options) {
  options.Validate();
  const std::unique_ptr<Crf> crf = ParseCrf(options.crf);
  const Dataset dataset =
      LoadDataset(root, {.image_check = ImageCheck::kNone, .require_test = false});
  std::vector<const Frame*> frames = dataset.AllFrames();
  for (const Frame* f : frames) {
    if (!f->hdr_path) {
      Fail(
          "{}: frame {} ({}) has no exr_file_path: LDR synthesis needs HDR ground truth for every "
          "frame",
          (root / fmt::format("transforms_{}.json", SplitName(f->split))).string(), f->index,
          f->file_path);
    }
  }
  if (frames.empty()) Fail("{}: the dataset has no frames", root.string());

  // Group by HDR file so each EXR is decoded once however many exposures use it.
  std::map<fs::path, std::vector<const Frame*>> by_hdr;
  for (const Frame* f : frames) by_hdr[*f->hdr_path].push_back(f);
  std::vector<std::pair<fs::path, std::vector<const Frame*>>> groups(by_hdr.begin(), by_hdr.end());

  Progress progress("synth-ldr", static_cast<std::int64_t>(frames.size()));
  std::vector<int> written(groups.size(), 0);
  // One group per task; inside SynthesizeLdr the pixels run in parallel too.
  ParallelFor(static_cast<std::int64_t>(groups.size()), 1, [&](std::int64_t g) {
    const Image hdr = ReadImage(groups[g].first);
    for (const Frame* f : groups[g].second) {
      if (!options.overwrite && fs::exists(f->image_path)) {
        progress.Advance();
        continue;
      }
      LdrSynthesisOptions ldr;
      ldr.exposure = f->exposure * std::exp(options.gain_drift * (f->time - 0.5));
      ldr.bits = options.bits;
      ldr.noise = options.noise;
      ldr.noise.seed =
          MixSeed(options.noise.seed ^ MixSeed(static_cast<std::uint64_t>(f->split) << 32 |
                                               static_cast<std::uint32_t>(f->index)));
      WriteImage(f->image_path, SynthesizeLdr(hdr.Rgb(), *crf, ldr),
                 {.format = options.bits == 16 ? PixelFormat::kUint16 : PixelFormat::kUint8});
      ++written[g];
      progress.Advance();
    }
  });
  progress.Finish();

  nlohmann::json manifest = {
      {"crf", crf->ToJson()},
      {"crf_spec", crf->Spec()},
      {"bits", options.bits},
      {"gain_drift", options.gain_drift},
      {"noise",
       {{"full_well", options.noise.full_well},
        {"read_sigma", options.noise.read_sigma},
        {"seed", options.noise.seed}}},
      {"frames", frames.size()},
  };
  WriteJsonFile(root / kManifestName, manifest);
  int total = 0;
  for (int w : written) total += w;
  return total;
}

void MergeOptions::Validate() const {
  if (split != "train" && split != "test" && split != "val" && split != "all") {
    Fail("merge-hdr: unknown split '{}' (use train, test, val or all)", split);
  }
  if (!crf.empty()) ParseCrf(crf);
}

int MergeDatasetExposures(const fs::path& root, const fs::path& out, const MergeOptions& options) {
  options.Validate();
  std::string crf_spec = options.crf;
  if (crf_spec.empty()) {
    const fs::path manifest = root / kManifestName;
    if (!fs::exists(manifest)) {
      Fail("{}: not found, so the camera response is unknown; pass --crf", manifest.string());
    }
    const nlohmann::json j = ReadJsonFile(manifest);
    if (!j.contains("crf_spec") || !j["crf_spec"].is_string())
      Fail("{}: key 'crf_spec' missing or not a string", manifest.string());
    crf_spec = j["crf_spec"].get<std::string>();
  }
  const std::unique_ptr<Crf> crf = ParseCrf(crf_spec);
  if (!crf->Invertible()) Fail("merge-hdr: the camera response '{}' is not invertible", crf_spec);
  const Dataset dataset =
      LoadDataset(root, {.image_check = ImageCheck::kHeaders, .require_test = false});

  std::map<fs::path, std::vector<const Frame*>> by_hdr;
  for (const Frame* f : FramesOfSplit(dataset, options.split)) {
    if (f->hdr_path) by_hdr[*f->hdr_path].push_back(f);
  }
  if (by_hdr.empty())
    Fail("{}: no {} frame has an exr_file_path to merge towards", root.string(), options.split);
  std::set<std::string> names;
  for (const auto& [hdr, frames] : by_hdr) {
    if (!names.insert(hdr.filename().string()).second) {
      Fail("{}: two HDR files share the name {}; merged outputs would overwrite each other",
           root.string(), hdr.filename().string());
    }
  }
  std::vector<std::pair<fs::path, std::vector<const Frame*>>> groups(by_hdr.begin(), by_hdr.end());
  Progress progress("merge-hdr", static_cast<std::int64_t>(groups.size()));
  ParallelFor(static_cast<std::int64_t>(groups.size()), 1, [&](std::int64_t g) {
    std::vector<Image> stack;
    std::vector<double> exposures;
    for (const Frame* f : groups[g].second) {
      stack.push_back(ReadImage(f->image_path).Rgb());
      exposures.push_back(f->exposure);
    }
    WriteImage(out / groups[g].first.filename(), MergeExposures(stack, exposures, *crf),
               {.format = PixelFormat::kFloat});
    progress.Advance();
  });
  progress.Finish();
  return static_cast<int>(groups.size());
}

}  // namespace hdr4d
