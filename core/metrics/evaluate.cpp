#include "core/metrics/evaluate.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <system_error>
#include <utility>
#include <vector>

#include "core/dataset/dataset.h"
#include "core/util/error.h"
#include "core/files/file_access.h"
#include "core/metrics/flip.h"
#include "core/metrics/hdr_alignment.h"
#include "core/image/image.h"
#include "core/image/image_io.h"
#include "core/image/image_resize.h"
#include "core/files/json_util.h"
#include "core/metrics/metrics.h"
#include "core/util/parallel.h"
#include "core/util/progress.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

struct PairResult {
  std::string name;
  MetricList metrics;
  bool identical = false;  // equal pixel values: every PSNR is +inf
  std::optional<LogShapeSums> fit_sums;  // behind the shape where the LDR fits (--ldr-fit)
  std::map<std::string, std::string> undefined;  // key -> why it has no value for this pair
};

const char* KindName(const Image& image) {
  return image.encoding() == Encoding::kLinear ? "HDR, float" : "LDR, integer";
}

// A ground-truth image as a run trained at --resolution R saw it (train_views.h): R x R box
// average, LDR then quantised to 8 bits as the training targets are.
Image ReadGroundTruth(const fs::path& path, int resolution) {
  Image image = ReadImage(path);
  if (resolution == 1) return image;
  if (std::string p = ResolutionProblem(image.width(), image.height(), resolution); !p.empty())
    Fail("{}: {}", path.string(), p);
  image = DownsampleBox(image, resolution);
  if (image.encoding() == Encoding::kSrgb)
    for (float& v : image.values()) v = std::round(std::clamp(v, 0.0f, 1.0f) * 255.0f) / 255.0f;
  return image;
}

// The pixel masks of an HDR ground truth from its LDR brackets (core/metrics/hdr_alignment.h): the
// measured pixels, and, with `ldr_fit` and renders named like some of the brackets in the
// prediction's folder, the pixels those renders reproduce.
struct BracketMasks {
  std::vector<std::uint8_t> measured;
  std::optional<std::vector<std::uint8_t>> reproduced;
};

std::optional<BracketMasks> ReadBracketMasks(const fs::path& gt_path,
                                             const fs::path& pred_path,
                                             const EvalBrackets* brackets,
                                             int resolution,
                                             bool ldr_fit) {
  if (!brackets) return std::nullopt;
  // By the ground truth's resolved path (datasets with sub-folders repeat file names), else by
  // its file name (a hand-made map).
  std::error_code ec;
  auto it = brackets->find(fs::weakly_canonical(gt_path, ec).string());
  if (it == brackets->end()) it = brackets->find(gt_path.filename().string());
  if (it == brackets->end() || it->second.empty()) return std::nullopt;
  std::vector<Image> ldr, truth_rendered, rendered;
  for (const fs::path& p : it->second) {
    ldr.push_back(ReadGroundTruth(p, resolution));
    const fs::path render = pred_path.parent_path() / p.filename();
    if (ldr_fit && render != p && fs::is_regular_file(render)) {
      rendered.push_back(ReadImage(render));
      truth_rendered.push_back(ldr.back());
    }
  }
  BracketMasks masks;
  try {
    masks.measured = MeasurableInBrackets(ldr);
    if (!rendered.empty()) masks.reproduced = ReproducedInBrackets(truth_rendered, rendered);
  } catch (const Error& e) {
    Fail("{}: its LDR brackets ({}, ...) or their renders in {}: {}", gt_path.string(),
         it->second[0].string(), pred_path.parent_path().string(), e.what());
  }
  return masks;
}

PairResult EvaluateFiles(const fs::path& pred_path,
                         const fs::path& gt_path,
                         const EvalBrackets* brackets,
                         int resolution,
                         bool ldr_fit) {
  const Image pred = ReadImage(pred_path);
  const Image gt = ReadGroundTruth(gt_path, resolution);
  // ReadImage marks float formats linear and integer formats display-encoded: that is the kind.
  if (pred.encoding() != gt.encoding()) {
    Fail("{} ({}) vs {} ({}): cannot compare an LDR image with an HDR one", pred_path.string(),
         KindName(pred), gt_path.string(), KindName(gt));
  }
  if (pred.width() != gt.width() || pred.height() != gt.height()) {
    Fail("{} ({}) vs {} ({}): images differ in size", pred_path.string(), pred.ShapeString(),
         gt_path.string(), gt.ShapeString());
  }
  // Metrics use the colour channels only (alpha ignored), so RGBA against RGB is fine, and grey +
  // alpha against grey. A grey truth is read as RGB against an RGB prediction, as training reads
  // it (a grey scene's renders are RGB); a grey prediction of an RGB truth is an error.
  const int pred_colour = pred.ColourChannelCount();
  const int gt_colour = gt.ColourChannelCount();
  const bool grey_truth = gt_colour == 1 && pred_colour == 3;
  if (pred_colour != gt_colour && !grey_truth) {
    Fail("{} ({}) vs {} ({}): images differ in colour channels ({} vs {})", pred_path.string(),
         pred.ShapeString(), gt_path.string(), gt.ShapeString(), pred_colour, gt_colour);
  }
  PairResult result;
  result.name = gt_path.filename().string();
  const bool hdr = gt.encoding() == Encoding::kLinear;
  const std::optional<BracketMasks> masks =
      hdr ? ReadBracketMasks(gt_path, pred_path, brackets, resolution, ldr_fit) : std::nullopt;
  const std::vector<std::uint8_t>* mask = masks ? &masks->measured : nullptr;
  if (mask && mask->size() != gt.num_pixels()) {
    Fail("{}: its LDR brackets are not the size of the HDR image ({})", gt_path.string(),
         gt.ShapeString());
  }
  try {
    const Image pred_rgb = pred.Rgb(), gt_rgb = grey_truth ? ExpandToRgb(gt) : gt.Rgb();
    if (hdr) {
      result.metrics = HdrMetrics(pred_rgb, gt_rgb);
      result.metrics.emplace_back("hdr_flip", HdrFlip(pred_rgb, gt_rgb));
      MetricList aligned = AlignedHdrMetrics(pred_rgb, gt_rgb, mask, /*with_flip=*/true);
      if (masks && masks->reproduced) {
        result.fit_sums.emplace();
        const MetricList fit =
            LdrFitHdrShape(pred_rgb, gt_rgb, *mask, *masks->reproduced, &*result.fit_sums);
        aligned.insert(aligned.end(), fit.begin(), fit.end());
      }
      for (auto& m : aligned) {
        if (std::isnan(m.second)) {
          result.undefined[m.first] = UndefinedMetricReason(m.first);
        } else {
          result.metrics.push_back(std::move(m));
        }
      }
    } else {
      result.metrics = LdrMetrics(pred_rgb, gt_rgb);
      result.metrics.emplace_back("flip", Flip(pred_rgb, gt_rgb));
    }
    result.identical = pred_rgb.values() == gt_rgb.values();
  } catch (const Error& e) {
    Fail("{} vs {}: {}", pred_path.string(), gt_path.string(), e.what());
  }
  return result;
}

nlohmann::json PairJson(const PairResult& pair) {
  nlohmann::json out = nlohmann::json::object();
  out["name"] = pair.name;
  for (const auto& [key, value] : pair.metrics) out[key] = FiniteOrNull(value);
  if (!pair.undefined.empty()) out["undefined"] = pair.undefined;
  return out;
}

// The images in `folder` and its sub-folders (renders keep a dataset's sub-folder layout,
// `cam0/x.png`), sorted by their path inside it.
std::vector<fs::path> ListImages(const fs::path& folder) {
  std::vector<fs::path> images;
  std::error_code ec;
  fs::recursive_directory_iterator it(folder, ec);
  if (ec) Fail("{}: cannot list folder: {}", folder.string(), ec.message());
  for (; it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (ec) Fail("{}: cannot list folder: {}", folder.string(), ec.message());
    std::error_code file_ec;
    // Only files ReadImage reads: JSON, logs and videos beside the images are ignored.
    if (it->is_regular_file(file_ec) && IsImagePath(it->path())) images.push_back(it->path());
  }
  if (ec) Fail("{}: cannot list folder: {}", folder.string(), ec.message());
  std::sort(images.begin(), images.end());
  return images;
}

// An image's name for pairing: its path inside the folder listed, with '/' separators.
std::string NameIn(const fs::path& image, const fs::path& folder) {
  return image.lexically_relative(folder).generic_string();
}

std::string JoinFirst(const std::vector<std::string>& names, std::size_t count) {
  std::string out;
  for (std::size_t i = 0; i < names.size() && i < count; ++i) out += (i ? ", " : "") + names[i];
  if (names.size() > count) out += fmt::format(", ... ({} more)", names.size() - count);
  return out;
}

// (prediction, ground truth) pairs, driven by the predictions: every prediction must have a
// ground truth (same file name, or the same stem with an extension of the same kind, LDR or
// HDR), while ground-truth images without a prediction are skipped with a warning, because a
// dataset keeps every split's images in one folder and a render covers one split. Predictions
// of a kind the ground-truth folder has none of are skipped with a warning too: a render folder
// holds LDR and HDR images side by side, and the dataset keeps them in separate folders.
std::vector<std::pair<fs::path, fs::path>> MatchFolders(const fs::path& pred_dir,
                                                        const fs::path& gt_dir) {
  const std::vector<fs::path> preds = ListImages(pred_dir);
  if (preds.empty()) {
    Fail(
        "{}: no predicted images in this folder (looked for .png, .jpg, .jpeg, .exr, .hdr, "
        ".tif, .tiff)",
        pred_dir.string());
  }
  std::map<std::string, fs::path> gt_by_name;
  std::map<std::string, std::vector<fs::path>> gt_by_stem;
  bool gt_has[2] = {false, false};  // [is HDR]
  for (const fs::path& g : ListImages(gt_dir)) {
    const fs::path name = NameIn(g, gt_dir);
    gt_by_name[name.generic_string()] = g;
    gt_by_stem[(name.parent_path() / name.stem()).generic_string()].push_back(g);
    gt_has[IsHdrPath(g)] = true;
  }
  std::size_t other_kind_skipped = 0;

  std::vector<std::pair<fs::path, fs::path>> pairs;
  std::vector<std::string> missing;
  for (const fs::path& pred : preds) {
    const std::string name = NameIn(pred, pred_dir);
    if (!gt_has[IsHdrPath(pred)] && gt_has[!IsHdrPath(pred)]) {
      ++other_kind_skipped;
      continue;
    }
    if (auto it = gt_by_name.find(name); it != gt_by_name.end()) {
      pairs.emplace_back(pred, it->second);
      continue;
    }
    std::vector<std::string> same_kind, other_kind;
    const fs::path stem = fs::path(name).parent_path() / pred.stem();
    if (auto it = gt_by_stem.find(stem.generic_string()); it != gt_by_stem.end()) {
      for (const fs::path& g : it->second)
        (IsHdrPath(g) == IsHdrPath(pred) ? same_kind : other_kind).push_back(NameIn(g, gt_dir));
    }
    if (same_kind.size() == 1) {
      pairs.emplace_back(pred, gt_dir / same_kind[0]);
    } else if (same_kind.size() > 1) {
      Fail("{}: several ground-truth images match prediction {}: {}", gt_dir.string(), name,
           JoinFirst(same_kind, 5));
    } else if (!other_kind.empty()) {
      missing.push_back(fmt::format("{} (only {} found, which is {})", name,
                                    JoinFirst(other_kind, 3), IsHdrPath(pred) ? "LDR" : "HDR"));
    } else {
      missing.push_back(name);
    }
  }
  if (!missing.empty()) {
    Fail("{}: no ground truth for {} of {} predicted images from {}: {}", gt_dir.string(),
         missing.size(), preds.size(), pred_dir.string(), JoinFirst(missing, 5));
  }
  if (pairs.empty()) {
    Fail("{}: holds only {} images, and none of the predictions in {} is of that kind",
         gt_dir.string(), gt_has[1] ? "HDR" : "LDR", pred_dir.string());
  }
  if (other_kind_skipped > 0) {
    spdlog::warn("eval: {} predicted images in {} are {} and {} has none of that kind: skipped",
                 other_kind_skipped, pred_dir.string(), gt_has[1] ? "LDR" : "HDR",
                 gt_dir.string());
  }
  const std::size_t unmatched = gt_by_name.size() - pairs.size();
  if (unmatched > 0) {
    spdlog::warn("eval: {} of {} ground-truth images in {} have no prediction and are skipped",
                 unmatched, gt_by_name.size(), gt_dir.string());
  }
  std::sort(pairs.begin(), pairs.end(), [&gt_dir](const auto& a, const auto& b) {
    return NameIn(a.second, gt_dir) < NameIn(b.second, gt_dir);
  });
  return pairs;
}

// Display order of the known keys in tables; unknown keys follow in name order.
const std::vector<std::string>& KnownKeys() {
  static const std::vector<std::string> keys = {
      "psnr",           "psnr_channel_mean", "ssim",      "flip",      "mu_psnr",
      "mu_ssim",        "mu_psnr_gt_max",    "mu_ssim_gt_max", "pu21_psnr", "pu21_ssim",
      "hdr_flip",       "hdr_flip_aligned",  "mu_psnr_aligned",   "mu_ssim_aligned", "pu21_psnr_aligned",
      "pu21_ssim_aligned", "hdr_log_slope",  "hdr_log_corr", "hdr_log_contrast",
      "hdr_align_scale", "hdr_measured_fraction", "hdr_log_slope_ldr_fit",
      "hdr_log_corr_ldr_fit", "hdr_ldr_fit_fraction"};
  return keys;
}

}  // namespace

EvalBrackets DatasetBrackets(const fs::path& scene, ExposureUnit unit) {
  const Dataset dataset =
      LoadDataset(scene, {.image_check = ImageCheck::kNone, .exposure_unit = unit});
  EvalBrackets out;
  for (const Frame* f : dataset.AllFrames()) {
    if (f->hdr_path) out[fs::weakly_canonical(*f->hdr_path).string()].push_back(f->image_path);
  }
  return out;
}

nlohmann::json EvaluatePair(const fs::path& pred,
                            const fs::path& gt,
                            const EvalBrackets* brackets,
                            int gt_resolution) {
  if (gt_resolution < 1) Fail("eval: --resolution {} must be >= 1", gt_resolution);
  return PairJson(EvaluateFiles(pred, gt, brackets, gt_resolution, false));
}

namespace {

// The pairs and their means as `eval` writes them.
nlohmann::json ResultsJson(const std::vector<std::optional<PairResult>>& results) {
  nlohmann::json out;
  out["pairs"] = nlohmann::json::array();
  // Sums in pair order over the finite values: one identical pair (PSNR +inf) must not turn every
  // mean into +inf and hide the others; it is counted in "identical_pairs" instead.
  std::map<std::string, std::pair<double, int>> sums;
  // Infinite values of pairs that are not identical (psnr_channel_mean where one channel is,
  // as the reference code computes it): left out of the mean too, and counted per key.
  std::map<std::string, int> left_out;
  int identical = 0;
  for (const auto& r : results) {
    out["pairs"].push_back(PairJson(*r));
    identical += r->identical ? 1 : 0;
    for (const auto& [key, value] : r->metrics) {
      auto& [sum, count] = sums[key];
      if (!std::isfinite(value)) {
        if (!r->identical) ++left_out[key];
        continue;
      }
      sum += value;
      ++count;
    }
  }
  out["mean"] = nlohmann::json::object();
  for (const auto& [key, sc] : sums)
    out["mean"][key] = sc.second > 0 ? FiniteOrNull(sc.first / sc.second) : nlohmann::json(nullptr);
  // The shape where the LDR fits: pooled within images, not the mean of per-pair slopes.
  std::vector<LogShapeSums> fit_sums;
  for (const auto& r : results)
    if (r->fit_sums) fit_sums.push_back(*r->fit_sums);
  if (!fit_sums.empty()) SetPooledLdrFitShape(fit_sums, &out["mean"]);
  out["identical_pairs"] = identical;
  if (!left_out.empty()) out["infinite_left_out"] = left_out;
  return out;
}

}  // namespace

nlohmann::json EvaluatePaths(const fs::path& pred,
                             const fs::path& gt,
                             const EvalBrackets* brackets,
                             int gt_resolution,
                             bool ldr_fit) {
  if (gt_resolution < 1) Fail("eval: --resolution {} must be >= 1", gt_resolution);
  std::error_code ec;
  for (const fs::path& p : {pred, gt}) {
    const PathProbe probe = ProbePath(p);  // "permission denied" is not "not found"
    if (probe.kind == PathKind::kMissing) Fail("{}: not found", p.string());
    if (probe.kind == PathKind::kUnknown || !probe.readable)
      Fail("{}: {}", p.string(), probe.problem);
    if (probe.kind == PathKind::kOther) RequireInputFile(p);  // devices, FIFOs, sockets
  }
  const bool pred_dir = fs::is_directory(pred, ec);
  const bool gt_dir = fs::is_directory(gt, ec);
  if (pred_dir != gt_dir) {
    Fail("{} is a {} but {} is a {}: give two image files or two folders", pred.string(),
         pred_dir ? "folder" : "file", gt.string(), gt_dir ? "folder" : "file");
  }
  std::vector<std::pair<fs::path, fs::path>> jobs;
  if (gt_dir) {
    jobs = MatchFolders(pred, gt);
  } else {
    jobs.emplace_back(pred, gt);
  }

  // Each pair writes its own slot; errors are collected too, and the first one in name order is
  // reported, so the outcome does not depend on scheduling.
  std::vector<std::optional<PairResult>> results(jobs.size());
  std::vector<std::string> errors(jobs.size());
  // A progress line for folders big enough to take a while (HDR metrics: ~0.2 s per 800x800 pair).
  constexpr std::size_t kProgressMinPairs = 16;
  Progress progress("eval", static_cast<std::int64_t>(jobs.size()),
                    jobs.size() >= kProgressMinPairs);
  ParallelFor(static_cast<std::int64_t>(jobs.size()), 1, [&](std::int64_t i) {
    try {
      results[i] = EvaluateFiles(jobs[i].first, jobs[i].second, brackets, gt_resolution, ldr_fit);
      if (gt_dir) results[i]->name = NameIn(jobs[i].second, gt);  // cam0/x.png: unique
    } catch (const std::exception& e) {
      errors[i] = e.what();
    }
    progress.Advance();
  });
  progress.Finish();
  std::size_t failed = 0;
  for (const std::string& e : errors) failed += e.empty() ? 0 : 1;
  for (const std::string& e : errors) {
    if (e.empty()) continue;
    if (failed == 1) throw Error(e);
    Fail("{} (and {} more pairs failed)", e, failed - 1);
  }

  return ResultsJson(results);
}

std::string FormatEvalTable(const nlohmann::json& result) {
  if (!result.is_object() || !result.contains("pairs") || !result["pairs"].is_array()) {
    Fail("evaluation result has no \"pairs\" list");
  }
  const nlohmann::json& pairs = result["pairs"];
  const nlohmann::json mean = result.value("mean", nlohmann::json::object());

  std::set<std::string> present;
  std::size_t name_width = 4;  // "mean"
  for (const auto& pair : pairs) {
    for (const auto& [key, value] : pair.items()) {
      if (key != "name" && key != "undefined") present.insert(key);
    }
    name_width = std::max(name_width, pair.value("name", std::string()).size());
  }
  std::vector<std::string> columns;
  for (const std::string& key : KnownKeys()) {
    if (present.erase(key)) columns.push_back(key);
  }
  columns.insert(columns.end(), present.begin(), present.end());

  auto cell = [](const nlohmann::json& row, const std::string& key) -> std::string {
    if (!row.contains(key)) return "-";
    const nlohmann::json& v = row[key];
    if (v.is_null()) return "inf";  // only +inf is written as null (NaN is rejected earlier)
    if (!v.is_number()) return "?";
    return fmt::format("{:.4f}", v.get<double>());
  };
  auto line = [&](const std::string& name, const nlohmann::json& row) {
    std::string s = fmt::format("{:<{}}", name, name_width);
    for (const std::string& key : columns) {
      s += fmt::format("  {:>{}}", cell(row, key), std::max<std::size_t>(key.size(), 9));
    }
    return s + "\n";
  };

  std::string out = fmt::format("{:<{}}", "name", name_width);
  for (const std::string& key : columns) {
    out += fmt::format("  {:>{}}", key, std::max<std::size_t>(key.size(), 9));
  }
  out += "\n";
  for (const auto& pair : pairs) out += line(pair.value("name", std::string("?")), pair);
  out += line("mean", mean);
  const int identical = result.value("identical_pairs", 0);
  if (identical > 0) {
    out += fmt::format(
        "identical: {} of {} pairs (PSNR inf there); the means are over the finite values\n",
        identical, pairs.size());
  }
  const nlohmann::json left_out = result.value("infinite_left_out", nlohmann::json::object());
  for (const auto& [key, count] : left_out.items()) {
    out += fmt::format("{}: inf on {} pair{} not identical (a channel is), left out of its mean\n",
                       key, count.get<int>(), count.get<int>() == 1 ? "" : "s");
  }
  return out;
}

}  // namespace hdr4d
