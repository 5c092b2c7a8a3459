#include "method/train/test_evaluation.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

#include "core/hdr_alignment.h"
#include "core/image_io.h"
#include "core/json_util.h"
#include "core/metrics.h"

namespace hdr4d::method {

nlohmann::json EvaluateViews(ViewRenderer* renderer, const std::vector<TrainView>& views) {
  nlohmann::json mean = nlohmann::json::object();
  if (views.empty()) return mean;
  std::map<std::string, std::pair<double, int>> sums;
  std::vector<float> ldr, hdr, gt;
  // The pixels some LDR bracket of the same view and time measures (the views sharing an HDR
  // ground truth), for the scale-aligned HDR metrics (core/hdr_alignment.h).
  std::map<std::filesystem::path, std::vector<Image>> brackets;
  for (const TrainView& v : views) {
    if (!v.hdr_path) continue;
    v.ToFloat(&gt);
    brackets[*v.hdr_path].push_back(DisplayImageFromBuffer(gt.data(), v.width(), v.height(), 3));
  }
  std::map<std::filesystem::path, std::vector<std::uint8_t>> measured;
  for (const auto& [path, images] : brackets) measured[path] = MeasurableInBrackets(images);
  for (const TrainView& v : views) {
    const ToneFrame frame{v.time_index, -1, static_cast<float>(std::log(v.exposure))};
    renderer->Render(v.camera, v.time, frame, &ldr, &hdr);
    // Means over the views where a metric is defined, as hdr4d eval does: the log-log slope
    // of a view with no measured pixel (every bracket clipped) is NaN and left out.
    auto add = [&](const MetricList& metrics) {
      for (const auto& [key, value] : metrics) {
        if (!std::isfinite(value)) continue;
        sums[key].first += value;
        sums[key].second += 1;
      }
    };
    if (!ldr.empty()) {
      v.ToFloat(&gt);
      add(LdrMetrics(DisplayImageFromBuffer(ldr.data(), v.width(), v.height(), 3),
                     DisplayImageFromBuffer(gt.data(), v.width(), v.height(), 3)));
    }
    if (!hdr.empty() && v.hdr_path) {
      Image prediction(v.width(), v.height(), 3, Encoding::kLinear);
      std::copy(hdr.begin(), hdr.end(), prediction.data());
      // A run at --resolution R compares with the truth reduced as its training target was.
      const Image file = ReadImage(*v.hdr_path);
      const int factor = file.width() / std::max(1, v.width());
      const Image truth = factor > 1 && ResolutionProblem(file.width(), file.height(), factor) == ""
                              ? DownsampleBox(file, factor)
                              : file;
      add(HdrMetrics(prediction, truth));
      add(AlignedHdrMetrics(prediction, truth, &measured.at(*v.hdr_path)));
    }
  }
  for (const auto& [key, sum] : sums) mean[key] = FiniteOrNull(sum.first / sum.second);
  return mean;
}

}  // namespace hdr4d::method
