#include "method/train/test_evaluation.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/metrics/flip.h"
#include "core/metrics/hdr_alignment.h"
#include "core/dataset/dataset_image_rules.h"
#include "core/image/image_io.h"
#include "core/files/json_util.h"
#include "core/metrics/metrics.h"

namespace hdr4d::method {

namespace {

// The views in groups that share one HDR ground truth (the brackets of one camera and time), in
// the order the truths first appear; a view without HDR truth is a group of its own.
std::vector<std::vector<std::size_t>> GroupByHdrTruth(const std::vector<TrainView>& views) {
  std::vector<std::vector<std::size_t>> groups;
  std::map<std::filesystem::path, std::size_t> group_of;
  for (std::size_t i = 0; i < views.size(); ++i) {
    if (!views[i].hdr_path) {
      groups.push_back({i});
      continue;
    }
    auto [it, added] = group_of.try_emplace(*views[i].hdr_path, groups.size());
    if (added) groups.emplace_back();
    groups[it->second].push_back(i);
  }
  return groups;
}

// The HDR metrics of `prediction` against the group's truth: raw, scale-aligned over the pixels
// some bracket of the group measures, and the shape where the rendered brackets `rendered` (one
// per view of the group, in its order) reproduce the truth's (core/metrics/hdr_alignment.h). A run at
// --resolution R compares with the truth reduced as its training target was. `with_flip`: also
// HDR-FLIP. `gt`: scratch; `fit_sums` receives the sums behind the shape where the LDR fits, for
// the split's pooled figure.
MetricList GroupHdrMetrics(const std::vector<TrainView>& views,
                           const std::vector<std::size_t>& group,
                           const std::vector<Image>& rendered,
                           const Image& prediction,
                           const std::filesystem::path& hdr_path,
                           bool with_flip,
                           std::vector<float>* gt,
                           std::vector<LogShapeSums>* fit_sums) {
  std::vector<Image> brackets;
  for (std::size_t i : group) {
    views[i].ToFloat(gt);
    brackets.push_back(DisplayImageFromBuffer(gt->data(), views[i].width(), views[i].height(), 3));
  }
  const std::vector<std::uint8_t> measured = MeasurableInBrackets(brackets);
  Image truth = ReadHdrGroundTruth(hdr_path).Rgb();  // RGBA ground truth: its colour
  const int factor = truth.width() / std::max(1, prediction.width());
  if (factor > 1 && ResolutionProblem(truth.width(), truth.height(), factor).empty())
    truth = DownsampleBox(truth, factor);
  MetricList metrics = HdrMetrics(prediction, truth);
  if (with_flip) metrics.emplace_back("hdr_flip", HdrFlip(prediction, truth));
  const MetricList aligned = AlignedHdrMetrics(prediction, truth, &measured, with_flip);
  metrics.insert(metrics.end(), aligned.begin(), aligned.end());
  if (rendered.size() == brackets.size()) {
    fit_sums->emplace_back();
    const MetricList fit = LdrFitHdrShape(
        prediction, truth, measured, ReproducedInBrackets(brackets, rendered), &fit_sums->back());
    metrics.insert(metrics.end(), fit.begin(), fit.end());
  }
  return metrics;
}

// A trained model's renderer as a RenderViewFn: each view at its own time and exposure.
RenderViewFn RenderEachView(ViewRenderer* renderer) {
  return [renderer](const TrainView& v, std::vector<float>* ldr, std::vector<float>* hdr) {
    const ToneFrame frame{v.time_index, -1, static_cast<float>(std::log(v.exposure)),
                           v.camera_index};
    renderer->Render(v.camera, v.time, frame, ldr, hdr);
  };
}

}  // namespace

nlohmann::json EvaluateViews(ViewRenderer* renderer,
                             const std::vector<TrainView>& views,
                             bool with_flip) {
  return EvaluateViews(RenderEachView(renderer), views, with_flip);
}

double MeanLdrPsnr(ViewRenderer* renderer, const std::vector<TrainView>& views) {
  return MeanLdrPsnr(RenderEachView(renderer), views);
}

double MeanLdrPsnr(const RenderViewFn& render, const std::vector<TrainView>& views) {
  double sum = 0;
  int count = 0;
  std::vector<float> ldr, gt;
  // EvaluateViews's order (the views grouped by HDR truth): the same sum, bit for bit.
  for (const std::vector<std::size_t>& group : GroupByHdrTruth(views)) {
    for (std::size_t i : group) {
      const TrainView& v = views[i];
      render(v, &ldr, /*hdr=*/nullptr);
      if (ldr.empty()) continue;
      v.ToFloat(&gt);
      const double psnr = Psnr(DisplayImageFromBuffer(ldr.data(), v.width(), v.height(), 3),
                               DisplayImageFromBuffer(gt.data(), v.width(), v.height(), 3));
      if (!std::isfinite(psnr)) continue;
      sum += psnr;
      ++count;
    }
  }
  return count > 0 ? sum / count : std::nan("");
}

nlohmann::json EvaluateViews(const RenderViewFn& render,
                             const std::vector<TrainView>& views,
                             bool with_flip) {
  nlohmann::json mean = nlohmann::json::object();
  if (views.empty()) return mean;
  std::map<std::string, std::pair<double, int>> sums;
  std::vector<float> ldr, hdr, gt;
  std::vector<LogShapeSums> fit_sums;  // one per HDR truth with rendered brackets
  // Means over the views where a metric is defined, as hdr4d eval does: the log-log slope of a
  // view with no measured pixel (every bracket clipped) is NaN and left out.
  auto add = [&](const MetricList& metrics) {
    for (const auto& [key, value] : metrics) {
      if (!std::isfinite(value)) continue;
      sums[key].first += value;
      sums[key].second += 1;
    }
  };
  // One HDR truth at a time, with its brackets: only one group's images are held (all of a
  // paper-size test split at once took 1.4 GB at 800x800, issue 15). The HDR render does not
  // depend on the exposure, so its metrics are computed once per truth and counted for every
  // bracket, as a mean over views needs.
  for (const std::vector<std::size_t>& group : GroupByHdrTruth(views)) {
    const std::optional<std::filesystem::path>& hdr_path = views[group.front()].hdr_path;
    std::vector<Image> rendered;  // the group's LDR renders, for the HDR's shape where they fit
    std::optional<Image> prediction;
    for (std::size_t i : group) {
      const TrainView& v = views[i];
      // The HDR image only where it is scored (the group's first view); the other brackets'
      // renders then blend the LDR channels alone (the same LDR image).
      render(v, &ldr, hdr_path && !prediction ? &hdr : nullptr);
      if (!ldr.empty()) {
        v.ToFloat(&gt);
        Image render = DisplayImageFromBuffer(ldr.data(), v.width(), v.height(), 3);
        const Image truth = DisplayImageFromBuffer(gt.data(), v.width(), v.height(), 3);
        add(LdrMetrics(render, truth));
        if (with_flip) add({{"flip", Flip(render, truth)}});
        if (hdr_path) rendered.push_back(std::move(render));
      }
      if (!hdr.empty() && hdr_path && !prediction) {
        prediction.emplace(v.width(), v.height(), 3, Encoding::kLinear);
        std::copy(hdr.begin(), hdr.end(), prediction->data());
      }
    }
    if (!prediction) continue;
    const MetricList hdr_metrics = GroupHdrMetrics(views, group, rendered, *prediction, *hdr_path,
                                                   with_flip, &gt, &fit_sums);
    for (std::size_t k = 0; k < group.size(); ++k) add(hdr_metrics);
  }
  for (const auto& [key, sum] : sums) mean[key] = FiniteOrNull(sum.first / sum.second);
  // The shape where the LDR fits is pooled within views, not a mean of per-view slopes.
  if (!fit_sums.empty()) SetPooledLdrFitShape(fit_sums, &mean);
  return mean;
}

}  // namespace hdr4d::method
