#include "core/radiometry/exposure_stack.h"

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <map>
#include <set>
#include <vector>

#include "core/files/atomic_file.h"
#include "core/radiometry/camera_pipeline_dataset.h"
#include "core/dataset/dataset.h"
#include "core/dataset/dataset_image_rules.h"
#include "core/util/error.h"
#include "core/files/file_access.h"
#include "core/image/image_io.h"
#include "core/files/dataset_folders.h"
#include "core/files/json_util.h"
#include "core/files/output_guard.h"
#include "core/radiometry/channel_crf.h"
#include "core/util/parallel.h"
#include "core/util/progress.h"

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
  pipeline.Validate();
}

namespace {

// Every frame of the dataset; each must have HDR ground truth.
std::vector<const Frame*> FramesWithHdr(const Dataset& dataset, const fs::path& root) {
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
  return frames;
}

// The files this command writes: the manifest and every frame's LDR image. The LDR images are
// its outputs, the HDR images its inputs: an LDR path that is an HDR file would destroy ground
// truth, so it is refused before anything is written.
std::vector<fs::path> LdrOutputs(const std::vector<const Frame*>& frames, const fs::path& root) {
  std::map<fs::path, const Frame*> hdr_inputs;
  for (const Frame* f : frames) hdr_inputs.emplace(fs::weakly_canonical(*f->hdr_path), f);
  std::vector<fs::path> outputs = {root / kManifestName};
  for (const Frame* f : frames) {
    if (const auto it = hdr_inputs.find(fs::weakly_canonical(f->image_path));
        it != hdr_inputs.end()) {
      Fail("{}: frame {}: file_path {} is the exr_file_path of {} frame {}: synthesising LDR there "
           "would overwrite the HDR ground truth",
           (root / fmt::format("transforms_{}.json", SplitName(f->split))).string(), f->index,
           f->file_path, SplitName(it->second->split), it->second->index);
    }
    outputs.push_back(f->image_path);
  }
  return outputs;
}

// The frames by HDR file, every HDR image's size checked against its frames' cameras from the
// headers, before any work.
std::map<fs::path, std::vector<const Frame*>> FramesByHdr(const std::vector<const Frame*>& frames) {
  std::map<fs::path, std::vector<const Frame*>> by_hdr;
  for (const Frame* f : frames) by_hdr[*f->hdr_path].push_back(f);
  for (const auto& [hdr_path, users] : by_hdr) {
    const ImageSpecInfo spec = ReadImageSpec(hdr_path);
    for (const Frame* f : users) {
      // The LDR image gets the camera's size: an HDR image of another size would make a
      // dataset whose images disagree with its JSON.
      const PinholeIntrinsics& k = f->camera.intrinsics;
      if (spec.width != k.width || spec.height != k.height) {
        Fail("{}: HDR image is {}x{}, but the camera of frame {} of transforms_{}.json is {}x{}",
             hdr_path.string(), spec.width, spec.height, f->index, SplitName(f->split), k.width,
             k.height);
      }
    }
  }
  return by_hdr;
}

// One frame's LDR image from its HDR ground truth: its exposure (with the gain drift over
// time) and noise seeded per frame.
Image SynthesizeFrame(const Frame& f,
                      const Image& hdr,
                      const fs::path& hdr_path,
                      const Crf& crf,
                      const DatasetPipeline& pipeline,
                      const DatasetSynthesisOptions& options) {
  LdrSynthesisOptions ldr;
  ldr.exposure = f.exposure * std::exp(options.gain_drift * (f.time - 0.5));
  ldr.bits = options.bits;
  ldr.noise = options.noise;
  ldr.noise.seed = MixSeed(options.noise.seed ^ MixSeed(static_cast<std::uint64_t>(f.split) << 32 |
                                                        static_cast<std::uint32_t>(f.index)));
  try {
    return pipeline.Synthesize(hdr.Rgb(), f, crf, ldr);
  } catch (const Error& e) {
    Fail("{}: {}", hdr_path.string(), e.what());
  }
}

void WriteManifest(const fs::path& root,
                   const Crf& crf,
                   const DatasetPipeline& pipeline,
                   const DatasetSynthesisOptions& options,
                   std::size_t frames) {
  nlohmann::json manifest = {
      {"crf", crf.ToJson()},
      {"crf_spec", crf.Spec()},
      {"bits", options.bits},
      {"gain_drift", options.gain_drift},
      {"noise",
       {{"full_well", options.noise.full_well},
        {"read_sigma", options.noise.read_sigma},
        {"seed", options.noise.seed}}},
      {"frames", frames},
  };
  if (!pipeline.Identity()) manifest["pipeline"] = pipeline.ToJson(root);
  WriteJsonFile(root / kManifestName, manifest);
}

// LDR images this command did not make (the scene has no synthesis.json: a capture's own
// photographs, or images from another tool) are replaced only when asked (issue 51 §6).
void RequireOwnLdrImages(const fs::path& root,
                         const std::vector<const Frame*>& frames,
                         const DatasetSynthesisOptions& options) {
  if (!options.overwrite || options.replace_foreign || PathExists(root / kManifestName)) return;
  std::vector<const Frame*> existing;
  for (const Frame* f : frames)
    if (PathExists(f->image_path)) existing.push_back(f);
  if (existing.empty()) return;
  Fail("{}: {} of its {} LDR images exist (e.g. {}) and the scene has no {}, so synth-ldr did "
       "not make them: refusing to replace them; pass --overwrite to replace them, or "
       "--keep-existing to write only the missing ones",
       root.string(), existing.size(), frames.size(), existing.front()->file_path, kManifestName);
}

// A folder of the scene that is a link into another scene (`dataset split-val` links its copy's
// images to the original's) would have the images written there: refused, naming both. A link
// to a folder of no scene (images kept on another disk) is written through.
// The folders `outputs` go into, each once.
std::set<fs::path> FoldersOf(const std::vector<fs::path>& outputs) {
  std::set<fs::path> folders;
  for (const fs::path& f : outputs) folders.insert(f.parent_path().empty() ? "." : f.parent_path());
  return folders;
}

void RequireOwnFolders(const fs::path& root, const std::vector<fs::path>& outputs) {
  std::error_code ec;
  const fs::path scene = fs::weakly_canonical(fs::absolute(root, ec), ec);
  for (const fs::path& folder : FoldersOf(outputs)) {
    const std::string owner = DatasetOfImageFolder(folder);
    if (owner.empty() || fs::path(owner) == scene) continue;
    Fail("{}: this folder of the scene {} is a link into the scene {} (as a `dataset split-val` "
         "copy shares its original's images): synth-ldr would rewrite that scene's images; run it "
         "on {} itself, or copy the folder instead of linking it",
         folder.string(), root.string(), owner, owner);
  }
}

// A folder the images go into that cannot be written is named with the cause before any work,
// not as the temporary file the first write fails on (issue 51 §24).
void RequireWritableFolders(const std::vector<fs::path>& outputs) {
  for (const fs::path& folder : FoldersOf(outputs)) {
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) continue;  // made by the writer, which names its problem
    if (::access(folder.c_str(), W_OK) == 0) continue;
    const int err = errno;
    Fail("{}: cannot write the scene's LDR images into this folder: {}", folder.string(),
         err == EROFS ? "it is on a read-only file system"
         : err == EACCES ? "it is read-only for this user (permission denied)"
                         : std::strerror(err));
  }
}

}  // namespace

int SynthesizeDatasetLdr(const fs::path& root, const DatasetSynthesisOptions& options) {
  options.Validate();
  const std::unique_ptr<Crf> crf = ParseCrf(options.crf);
  const Dataset dataset = LoadDataset(root, {.image_check = ImageCheck::kNone,
                                             .exposure_unit = options.exposure_unit,
                                             .require_test = false});
  const std::vector<const Frame*> frames = FramesWithHdr(dataset, root);
  // Writing a dataset's LDR images is this command's job: the output guard lets exactly these
  // files through (core/files/output_guard.h), nothing else in the dataset's folders.
  const std::vector<fs::path> outputs = LdrOutputs(frames, root);
  RequireOwnLdrImages(root, frames, options);
  RequireOwnFolders(root, outputs);
  RequireWritableFolders(outputs);
  const OutputPermit permit(outputs);
  const std::map<fs::path, std::vector<const Frame*>> by_hdr = FramesByHdr(frames);

  const DatasetPipeline pipeline(options.pipeline, options.crf, frames);

  // Grouped by HDR file so each EXR is decoded once however many exposures use it.
  std::vector<std::pair<fs::path, std::vector<const Frame*>>> groups(by_hdr.begin(), by_hdr.end());
  // All or nothing: a bad HDR image found halfway leaves the previous LDR images, not a mix.
  FileBatch batch;

  Progress progress("synth-ldr", static_cast<std::int64_t>(frames.size()));
  std::vector<int> written(groups.size(), 0);
  // One group per task; inside SynthesizeLdr the pixels run in parallel too.
  ParallelFor(static_cast<std::int64_t>(groups.size()), 1, [&](std::int64_t g) {
    const fs::path& hdr_path = groups[g].first;
    const Image hdr = ReadHdrGroundTruth(hdr_path);
    for (const Frame* f : groups[g].second) {
      if (!options.overwrite && PathExists(f->image_path)) {
        progress.Advance();
        continue;
      }
      const Image image = SynthesizeFrame(*f, hdr, hdr_path, *crf, pipeline, options);
      WriteImage(f->image_path, image,
                 {.format = options.bits == 16 ? PixelFormat::kUint16 : PixelFormat::kUint8,
                  .batch = &batch});
      ++written[g];
      progress.Advance();
    }
  });
  progress.Finish();
  batch.Commit();
  WriteManifest(root, *crf, pipeline, options, frames.size());
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

namespace {

// One curve for all channels, or each colour channel merged with its own (calibrate's
// response.csv); alpha and further channels use the last curve.
Image MergeWithChannelCrfs(const std::vector<Image>& stack, const std::vector<double>& exposures,
                           const std::vector<std::unique_ptr<Crf>>& crfs) {
  if (crfs.size() == 1) return MergeExposures(stack, exposures, *crfs.front());
  const Image& first = stack.front();
  Image merged(first.width(), first.height(), first.channels(), Encoding::kLinear);
  for (int c = 0; c < first.channels(); ++c) {
    std::vector<Image> plane;
    for (const Image& image : stack) {
      Image p(image.width(), image.height(), 1, image.encoding());
      for (std::size_t i = 0; i < p.num_pixels(); ++i) p.data()[i] = image.data()[i * image.channels() + c];
      plane.push_back(std::move(p));
    }
    const Image m = MergeExposures(plane, exposures, *crfs[std::min<std::size_t>(c, crfs.size() - 1)]);
    for (std::size_t i = 0; i < m.num_pixels(); ++i) merged.data()[i * first.channels() + c] = m.data()[i];
  }
  return merged;
}

// Whether any value of any bracket lies strictly inside (0, 1): a measurement, not a clip.
bool AnyMeasuredValue(const std::vector<Image>& stack) {
  for (const Image& image : stack)
    for (float v : image.values())
      if (v > 0.0f && v < 1.0f) return true;
  return false;
}

// Brackets clipped everywhere merge to a constant that says nothing of the scene (issue 51 §18):
// said once, naming the first such image and the count.
void WarnUnmeasured(const std::vector<std::pair<fs::path, std::vector<const Frame*>>>& groups,
                    const std::vector<char>& unmeasured) {
  std::size_t count = 0;
  const fs::path* first = nullptr;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    if (!unmeasured[g]) continue;
    if (!first) first = &groups[g].first;
    ++count;
  }
  if (count == 0) return;
  spdlog::warn("merge-hdr: {} of {} merged images (e.g. {}) have no pixel "
               "measured in any exposure: every bracket is clipped at 0 or 1 everywhere, so the "
               "merged HDR is a constant, not the scene's radiance",
               count, groups.size(), first->filename().string());
}

}  // namespace

int MergeDatasetExposures(const fs::path& root, const fs::path& out, const MergeOptions& options) {
  options.Validate();
  std::string crf_spec = options.crf;
  if (crf_spec.empty()) {
    const fs::path manifest = root / kManifestName;
    if (!PathExists(manifest)) {
      Fail("{}: not found, so the camera response is unknown; pass --crf", manifest.string());
    }
    const nlohmann::json j = ReadJsonFile(manifest);
    if (!j.contains("crf_spec") || !j["crf_spec"].is_string())
      Fail("{}: key 'crf_spec' missing or not a string", manifest.string());
    crf_spec = j["crf_spec"].get<std::string>();
    if (j.contains("pipeline"))  // per-view gains and curves: no one response inverts them
      Fail("{}: the LDR images went through the camera pipeline '{}', not one response; pass "
           "--crf to merge with one anyway",
           manifest.string(), j["pipeline"].value("name", "?"));
  }
  std::vector<std::unique_ptr<Crf>> crfs;
  try {
    crfs = ParseChannelCrfs(crf_spec);
  } catch (const Error& e) {
    if (!options.crf.empty()) throw;  // given with --crf: the message names it
    Fail("{}: crf_spec: {}", (root / kManifestName).string(), e.what());
  }
  for (const auto& crf : crfs)
    if (!crf->Invertible()) Fail("merge-hdr: the camera response '{}' is not invertible", crf_spec);
  const Dataset dataset = LoadDataset(root, {.image_check = ImageCheck::kHeaders,
                                             .exposure_unit = options.exposure_unit,
                                             .require_test = false});

  std::map<fs::path, std::vector<const Frame*>> by_hdr;
  for (const Frame* f : FramesOfSplit(dataset, options.split)) {
    if (f->hdr_path) by_hdr[*f->hdr_path].push_back(f);
  }
  if (by_hdr.empty())
    Fail("{}: no {} frame has an exr_file_path to merge towards", root.string(), options.split);
  // Before any work: the output folder may not be one of the dataset's image folders.
  CheckOutputFolder(out);
  std::set<std::string> names;
  for (const auto& [hdr, frames] : by_hdr) {
    if (!names.insert(hdr.filename().string()).second) {
      Fail("{}: two HDR files share the name {}; merged outputs would overwrite each other",
           root.string(), hdr.filename().string());
    }
    // Outputs are named like the ground truth, as `render` names its HDR images: a folder of
    // renders given as --out would lose them.
    if (!options.overwrite && PathExists(out / hdr.filename()))
      Fail("{}: exists; merge-hdr replaces no file unless told to (--overwrite), give another "
           "--out", (out / hdr.filename()).string());
  }
  std::vector<std::pair<fs::path, std::vector<const Frame*>>> groups(by_hdr.begin(), by_hdr.end());
  FileBatch batch;  // all merged images or none
  Progress progress("merge-hdr", static_cast<std::int64_t>(groups.size()));
  std::vector<char> unmeasured(groups.size(), 0);
  ParallelFor(static_cast<std::int64_t>(groups.size()), 1, [&](std::int64_t g) {
    std::vector<Image> stack;
    std::vector<double> exposures;
    for (const Frame* f : groups[g].second) {
      stack.push_back(ExpandToRgb(ReadImage(f->image_path)));  // a grey frame among RGB ones
      exposures.push_back(f->exposure);
    }
    unmeasured[g] = !AnyMeasuredValue(stack);
    WriteImage(out / groups[g].first.filename(), MergeWithChannelCrfs(stack, exposures, crfs),
               {.format = PixelFormat::kFloat, .batch = &batch});
    progress.Advance();
  });
  progress.Finish();
  batch.Commit();
  WarnUnmeasured(groups, unmeasured);
  return static_cast<int>(groups.size());
}

}  // namespace hdr4d
