#include "benchmark/scoring.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "core/util/error.h"
#include "core/metrics/evaluate.h"
#include "core/image/image_io.h"
#include "core/metrics/metrics.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;
namespace {

constexpr int kRegionGrid = 8;

// Mean luminance of the region (fractions) of an image: linear luminance for HDR, luma of the
// stored values for LDR.
double RegionMean(const Image& image, const std::array<double, 4>& r) {
  const int x0 = static_cast<int>(std::floor(r[0] * image.width()));
  const int y0 = static_cast<int>(std::floor(r[1] * image.height()));
  const int x1 = std::max(x0 + 1, static_cast<int>(std::ceil((r[0] + r[2]) * image.width())));
  const int y1 = std::max(y0 + 1, static_cast<int>(std::ceil((r[1] + r[3]) * image.height())));
  double sum = 0;
  int n = 0;
  for (int y = y0; y < std::min(y1, image.height()); ++y) {
    for (int x = x0; x < std::min(x1, image.width()); ++x) {
      const int c = image.channels();
      sum += c >= 3 ? Luminance(image.at(x, y, 0), image.at(x, y, 1), image.at(x, y, 2))
                    : image.at(x, y, 0);
      ++n;
    }
  }
  return n ? sum / n : std::nan("");
}

std::string List(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t i = 0; i < names.size() && i < 5; ++i) s += (i ? ", " : "") + names[i];
  if (names.size() > 5) s += fmt::format(" and {} more", names.size() - 5);
  return s;
}

}  // namespace

std::string LdrRenderName(const Frame& frame) {
  fs::path name = frame.image_path.filename();
  if (name.extension() != ".png") name += ".png";
  return name.string();
}

std::string HdrRenderName(const Frame& frame) {
  fs::path name = frame.hdr_path ? frame.hdr_path->filename() : frame.image_path.stem();
  if (name.extension() != ".exr") name += ".exr";
  return name.string();
}

std::array<double, 4> RegionFromGroundTruth(const Dataset& dataset, Split split, int camera) {
  const double cell = 1.0 / kRegionGrid;
  std::vector<std::vector<double>> values(kRegionGrid * kRegionGrid);
  std::set<fs::path> seen;
  for (const Frame& f : dataset.FramesOf(split)) {
    if (f.camera_id != camera) continue;
    const fs::path gt = f.hdr_path && fs::exists(*f.hdr_path) ? *f.hdr_path : f.image_path;
    if (!fs::exists(gt) || !seen.insert(gt).second) continue;
    const Image image = ReadImage(gt);
    for (int j = 0; j < kRegionGrid; ++j)
      for (int i = 0; i < kRegionGrid; ++i)
        values[j * kRegionGrid + i].push_back(
            std::log(std::max(RegionMean(image, {i * cell, j * cell, cell, cell}), 1e-12)));
  }
  int best = (kRegionGrid / 2) * kRegionGrid + kRegionGrid / 2;  // the centre when no variation
  double best_var = 0;
  for (int k = 0; k < kRegionGrid * kRegionGrid; ++k) {
    const auto& v = values[k];
    if (v.size() < 2) continue;
    double mean = 0, var = 0;
    for (double x : v) mean += x;
    mean /= v.size();
    for (double x : v) var += (x - mean) * (x - mean);
    if (var > best_var * (1 + 1e-9) + 1e-12) {
      best_var = var;
      best = k;
    }
  }
  return {(best % kRegionGrid) * cell, (best / kRegionGrid) * cell, cell, cell};
}

namespace {

// An expected render and its ground truth.
struct Expected {
  std::string name;
  fs::path gt;
  const Frame* frame;
  bool hdr;
};

// Expected renders: one per LDR ground truth, one per distinct HDR ground truth.
void ExpectRenders(const std::vector<Frame>& frames,
                   std::vector<Expected>* ldr,
                   std::vector<Expected>* hdr) {
  std::set<std::string> hdr_names;
  for (const Frame& f : frames) {
    if (fs::exists(f.image_path)) ldr->push_back({LdrRenderName(f), f.image_path, &f, false});
    if (f.hdr_path && hdr_names.insert(HdrRenderName(f)).second)
      hdr->push_back({HdrRenderName(f), *f.hdr_path, &f, true});
  }
}

// The expected renders the folder has. A kind is either absent (the method does not output it)
// or complete.
std::vector<const Expected*> PresentRenders(const std::vector<Expected>& ldr,
                                            const std::vector<Expected>& hdr,
                                            const fs::path& renders,
                                            Split split) {
  std::vector<const Expected*> todo;
  for (const auto* list : {&ldr, &hdr}) {
    std::vector<std::string> missing;
    std::size_t present = 0;
    for (const Expected& e : *list) {
      if (fs::exists(renders / e.name)) {
        ++present;
        todo.push_back(&e);
      } else {
        missing.push_back(e.name);
      }
    }
    if (present > 0 && !missing.empty()) {
      Fail("{}: {} of the {} {} renders of the {} split are missing: {}", renders.string(),
           missing.size(), list->size(), list == &ldr ? "LDR" : "HDR", SplitName(split),
           List(missing));
    }
  }
  return todo;
}

// Strict scoring: no image in the folder but the expected renders.
void RefuseExtraImages(const std::vector<Expected>& ldr,
                       const std::vector<Expected>& hdr,
                       const fs::path& renders,
                       Split split) {
  std::set<std::string> expected_names;
  for (const auto* list : {&ldr, &hdr})
    for (const Expected& e : *list) expected_names.insert(e.name);
  std::vector<std::string> extra;
  for (const auto& entry : fs::directory_iterator(renders)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_regular_file() && IsImagePath(entry.path()) && !expected_names.count(name))
      extra.push_back(name);
  }
  std::sort(extra.begin(), extra.end());
  if (!extra.empty()) {
    Fail(
        "{}: {} image(s) are not renders of the {} split's views (names must match the ground "
        "truth): {}",
        renders.string(), extra.size(), SplitName(split), List(extra));
  }
}

// One render against its ground truth: every metric of `hdr4d eval`, and the region's mean.
FrameResult ScoreFrame(const Expected& e,
                       const fs::path& renders,
                       const std::array<double, 4>& region) {
  const fs::path pred = renders / e.name;
  const nlohmann::json pair = EvaluatePair(pred, e.gt);  // throws naming both files
  FrameResult fr;
  fr.frame = e.hdr ? *e.frame->exr_file_path : e.frame->file_path;
  fr.time = e.frame->time;
  fr.camera_id = e.frame->camera_id;
  fr.exposure = e.hdr ? 0.0 : e.frame->exposure;
  for (const auto& [key, value] : pair.items()) {
    // "undefined" lists the metrics this pair has no value for (a constant truth), with why.
    if (key == "name" || key == "undefined") continue;
    // EvaluatePair writes +inf (identical images) as null.
    fr.metrics[key] =
        value.is_null() ? std::numeric_limits<double>::infinity() : value.get<double>();
  }
  const std::string prefix = e.hdr ? "region_luminance" : "region_ldr";
  fr.stats[prefix] = RegionMean(ReadImage(pred), region);
  fr.stats[prefix + "_gt"] = RegionMean(ReadImage(e.gt), region);
  return fr;
}

}  // namespace

ScoredRenders ScoreRenders(const Dataset& dataset,
                           const fs::path& renders,
                           const ScoringOptions& options) {
  if (!fs::is_directory(renders)) Fail("{}: no such folder of renders", renders.string());
  const std::vector<Frame>& frames = dataset.FramesOf(options.split);
  if (frames.empty())
    Fail("{}: the {} split has no frames", dataset.root.string(), SplitName(options.split));
  std::vector<Expected> ldr, hdr;
  ExpectRenders(frames, &ldr, &hdr);
  const std::vector<const Expected*> todo = PresentRenders(ldr, hdr, renders, options.split);
  if (options.strict) RefuseExtraImages(ldr, hdr, renders, options.split);
  if (todo.empty()) {
    Fail("{}: no render is named like a ground-truth image of the {} split (e.g. {})",
         renders.string(), SplitName(options.split),
         !ldr.empty() ? ldr.front().name : (!hdr.empty() ? hdr.front().name : "?"));
  }
  ScoredRenders out;
  out.region_camera = frames.front().camera_id;
  out.region = options.region.value_or(RegionFromGroundTruth(dataset, options.split, out.region_camera));
  for (const Expected* e : todo) out.frames.push_back(ScoreFrame(*e, renders, out.region));
  return out;
}

}  // namespace hdr4d::bench
