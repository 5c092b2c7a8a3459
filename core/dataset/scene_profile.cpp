#include "core/dataset/scene_profile.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>

namespace hdr4d {

namespace {

// Sorted distinct values, merging neighbours closer than `tolerance(value)`.
template <typename Tol>
std::vector<double> Distinct(std::vector<double> values, Tol tolerance) {
  std::sort(values.begin(), values.end());
  std::vector<double> out;
  for (double v : values) {
    if (out.empty() || v - out.back() > tolerance(out.back())) out.push_back(v);
  }
  return out;
}

// A pose quantised to kSamePoseTolerance, so equal poses read from float32 JSON compare equal
// without an O(n^2) search.
using PoseKey = std::array<long long, 12>;
PoseKey KeyOf(const Eigen::Matrix4d& pose) {
  PoseKey key{};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) key[r * 4 + c] = std::llround(pose(r, c) / kSamePoseTolerance);
  }
  return key;
}

std::string JoinNumbers(const std::vector<double>& values) {
  std::string s;
  for (std::size_t i = 0; i < values.size(); ++i)
    s += (i ? ", " : "") + fmt::format("{:g}", values[i]);
  return s;
}

}  // namespace

SceneProfile ProfileScene(const Dataset& dataset) {
  SceneProfile p;
  const std::vector<const Frame*> frames = dataset.AllFrames();
  p.num_frames = static_cast<int>(frames.size());
  if (frames.empty()) return p;

  std::vector<double> times, exposures;
  std::set<int> camera_ids;
  std::set<PoseKey> poses;
  for (const Frame* f : frames) {
    times.push_back(f->time);
    exposures.push_back(f->exposure);
    if (f->camera_id >= 0) camera_ids.insert(f->camera_id);
    poses.insert(KeyOf(f->camera.world_from_cam_gl));
    if (f->hdr_path) ++p.num_hdr_frames;
  }
  const std::vector<double> distinct_times =
      Distinct(times, [](double) { return kSameTimeTolerance; });
  p.exposures =
      Distinct(exposures, [](double v) { return kSameExposureRelTolerance * std::abs(v); });
  p.exposures_unread = dataset.exposures_look_like_stops;
  if (p.exposures_unread) p.exposures.clear();  // the defaults of refused values, not the scene's
  p.num_timestamps = static_cast<int>(distinct_times.size());
  p.dynamic = p.num_timestamps > 1;
  p.multi_exposure = p.exposures.size() > 1;
  p.time_min = distinct_times.front();
  p.time_max = distinct_times.back();
  p.width = frames.front()->camera.intrinsics.width;
  p.height = frames.front()->camera.intrinsics.height;

  const bool all_test_hdr =
      !dataset.test.empty() && std::all_of(dataset.test.begin(), dataset.test.end(),
                                           [](const Frame& f) { return f.hdr_path.has_value(); });
  p.has_hdr_gt = all_test_hdr;
  p.partial_hdr_gt = !all_test_hdr && p.num_hdr_frames > 0;
  p.hdr_gt_in_train = std::any_of(dataset.train.begin(), dataset.train.end(),
                                  [](const Frame& f) { return f.hdr_path.has_value(); });

  // Multi-view: at an instant the training set sees the scene from several poses. Only train
  // frames count: D-NeRF's test views share timestamps with train views of a single moving
  // camera. It must hold for at least half of the training instants, so a monocular capture
  // with one accidental repeated time is still monocular.
  std::map<long long, std::set<PoseKey>> poses_at_time;
  for (const Frame& f : dataset.train) {
    poses_at_time[std::llround(f.time / kSameTimeTolerance)].insert(
        KeyOf(f.camera.world_from_cam_gl));
  }
  int shared = 0;
  for (const auto& [t, at_t] : poses_at_time) shared += at_t.size() > 1;
  const bool shared_instants =
      !poses_at_time.empty() && 2 * shared >= static_cast<int>(poses_at_time.size());
  p.multi_view = camera_ids.size() > 1 || shared_instants;
  p.num_cameras =
      !camera_ids.empty() ? static_cast<int>(camera_ids.size()) : static_cast<int>(poses.size());
  return p;
}

std::string SceneProfile::Describe() const {
  std::string s;
  auto line = [&s](const std::string& text) { s += text + "\n"; };
  if (num_frames == 0) {
    line("empty: no frames");
    return s;
  }
  if (dynamic) {
    line(
        fmt::format("dynamic: {} timestamps in [{:g}, {:g}]: trains the time axis and the tone "
                    "mapper's temporal context",
                    num_timestamps, time_min, time_max));
  } else {
    line(
        fmt::format("static: one timestamp ({:g}): trains without the time axis (3D Gaussians, "
                    "no temporal marginal, no temporal context)",
                    time_min));
  }
  if (exposures_unread) {
    line("exposures: not read (they look like log2 stops, not seconds: --exposure-unit stops)");
  } else if (multi_exposure) {
    line(
        fmt::format("multi-exposure: {} exposures ({} s): learns the tone curve from the "
                    "brackets",
                    exposures.size(), JoinNumbers(exposures)));
  } else {
    line(
        fmt::format("single exposure ({} s): the tone curve is seen at one exposure only; HDR is "
                    "not constrained beyond the LDR range",
                    JoinNumbers(exposures)));
  }
  if (has_hdr_gt) {
    line(fmt::format(
        "HDR ground truth: every test frame ({} frames with HDR): HDR metrics computed{}",
        num_hdr_frames, hdr_gt_in_train ? "; HDR loss on training frames" : ""));
  } else if (partial_hdr_gt) {
    line(
        fmt::format("partial HDR ground truth ({} of {} frames): HDR loss and metrics only where "
                    "it exists",
                    num_hdr_frames, num_frames));
  } else {
    line("no HDR ground truth: HDR loss and HDR metrics skipped");
  }
  if (multi_view) {
    line(fmt::format("multi-view: {} cameras see each instant", num_cameras));
  } else {
    line(fmt::format("monocular: one moving camera ({} distinct poses)", num_cameras));
  }
  line(fmt::format("resolution: {}x{}, {} frames", width, height, num_frames));
  return s;
}

nlohmann::json SceneProfile::ToJson() const {
  return {
      {"dynamic", dynamic},
      {"multi_exposure", multi_exposure},
      {"has_hdr_gt", has_hdr_gt},
      {"partial_hdr_gt", partial_hdr_gt},
      {"hdr_gt_in_train", hdr_gt_in_train},
      {"multi_view", multi_view},
      {"num_cameras", num_cameras},
      {"num_timestamps", num_timestamps},
      {"num_frames", num_frames},
      {"num_hdr_frames", num_hdr_frames},
      {"exposures", exposures},
      {"exposures_unread", exposures_unread},
      {"time_min", time_min},
      {"time_max", time_max},
      {"width", width},
      {"height", height},
  };
}

}  // namespace hdr4d
