#include "core/dataset/dataset_check_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <optional>
#include <set>
#include <vector>

#include "core/dataset/scene_profile.h"

namespace hdr4d {
namespace {

const char* HdrGroundTruth(const SceneProfile& profile) {
  return profile.has_hdr_gt ? "yes" : profile.partial_hdr_gt ? "partial" : "no";
}

// The distinct `exposures` numbers as the JSON wrote them (seconds or stops), ascending.
std::vector<double> WrittenExposures(const Dataset& d) {
  std::set<double> values;
  for (const Frame* f : d.AllFrames()) {
    if (f->exposure_written) values.insert(*f->exposure_written);
  }
  return {values.begin(), values.end()};
}

std::string JoinValues(const std::vector<double>& values) {
  std::string out;
  for (double v : values) out += (out.empty() ? "" : ", ") + fmt::format("{:g}", v);
  return out;
}

// Seconds, with what was written when it was not seconds; never seconds for values that were
// not read as such (+1 stop is not "1 s").
std::string ExposureLine(const nlohmann::json& s, const SceneProfile& profile) {
  const auto written = s["exposures_written"].get<std::vector<double>>();
  if (s["exposures_look_like_stops"].get<bool>()) {
    return fmt::format("not read: written as {} (log2 stops? see the problem above)",
                       JoinValues(written));
  }
  const std::string as_written =
      s["exposure_unit"] == "stops" ? "; written as " + JoinValues(written) + " stops" : "";
  return fmt::format("{} distinct ({} s{})", profile.exposures.size(),
                     JoinValues(profile.exposures), as_written);
}

nlohmann::json Summary(const DatasetReport& report, const SceneProfile& profile) {
  const Dataset& d = *report.dataset;
  double raw_min = std::numeric_limits<double>::infinity(), raw_max = 0;
  for (const Frame* f : d.AllFrames()) {
    raw_min = std::min(raw_min, f->time_raw);
    raw_max = std::max(raw_max, f->time_raw);
  }
  if (d.NumFrames() == 0) raw_min = 0;
  nlohmann::json point_cloud = nullptr;
  if (d.point_cloud_path) {
    point_cloud = {{"path", d.point_cloud_path->string()},
                   {"points", report.point_cloud_points ? nlohmann::json(*report.point_cloud_points)
                                                        : nlohmann::json(nullptr)}};
  }
  return {
      {"root", d.root.string()},
      {"layout", d.layout},
      {"frames", {{"train", d.train.size()}, {"test", d.test.size()}, {"val", d.val.size()}}},
      {"cameras", profile.num_cameras},
      {"exposures", profile.exposures},
      {"exposure_unit", ExposureUnitName(d.exposure_unit)},
      {"exposures_written", WrittenExposures(d)},
      {"exposures_look_like_stops", d.exposures_look_like_stops},
      {"time_raw", {{"min", raw_min}, {"max", raw_max}}},
      {"time", {{"min", profile.time_min}, {"max", profile.time_max}}},
      {"hdr_gt", HdrGroundTruth(profile)},
      {"resolution", {{"width", profile.width}, {"height", profile.height}}},
      {"camera_angle_x", d.camera_angle_x},
      {"point_cloud", point_cloud},
  };
}

std::string SummaryText(const nlohmann::json& s, const SceneProfile& profile) {
  std::string out;
  auto line = [&out](const std::string& text) { out += text + "\n"; };
  line(fmt::format("dataset: {}", s["root"].get<std::string>()));
  line(fmt::format("  layout:      {}", s["layout"].get<std::string>()));
  line(fmt::format("  frames:      {} train, {} test, {} val", s["frames"]["train"].get<int>(),
                   s["frames"]["test"].get<int>(), s["frames"]["val"].get<int>()));
  line(fmt::format("  cameras:     {}", s["cameras"].get<int>()));
  line("  exposures:   " + ExposureLine(s, profile));
  line(fmt::format("  time:        raw [{:g}, {:g}], normalised [{:g}, {:g}]",
                   s["time_raw"]["min"].get<double>(), s["time_raw"]["max"].get<double>(),
                   profile.time_min, profile.time_max));
  line(fmt::format("  HDR GT:      {} ({} frames with exr_file_path)",
                   s["hdr_gt"].get<std::string>(), profile.num_hdr_frames));
  line(fmt::format("  resolution:  {}x{}", profile.width, profile.height));
  if (s["point_cloud"].is_null()) {
    line("  point cloud: none (point3d.ply absent: random initialisation)");
  } else if (s["point_cloud"]["points"].is_null()) {
    line(
        fmt::format("  point cloud: {} (unreadable)", s["point_cloud"]["path"].get<std::string>()));
  } else {
    line(fmt::format("  point cloud: {} points", s["point_cloud"]["points"].get<std::int64_t>()));
  }
  line("profile:");
  std::string described = profile.Describe();
  std::size_t start = 0;
  while (start < described.size()) {
    const std::size_t end = described.find('\n', start);
    line("  " + described.substr(start, end - start));
    start = end == std::string::npos ? described.size() : end + 1;
  }
  return out;
}

}  // namespace

nlohmann::json DatasetReportJson(const DatasetReport& report) {
  std::optional<SceneProfile> profile;
  nlohmann::json summary = nullptr;
  if (report.dataset) {
    profile = ProfileScene(*report.dataset);
    summary = Summary(report, *profile);
  }
  nlohmann::json problems = nlohmann::json::array();
  for (const DatasetProblem& p : report.problems) {
    problems.push_back({{"file", p.file.string()},
                        {"frame", p.frame},
                        {"key", p.key},
                        {"message", p.message},
                        {"text", p.ToString()}});
  }
  return {{"ok", report.ok()},
          {"problems", problems},
          {"summary", summary},
          {"profile", profile ? profile->ToJson() : nlohmann::json(nullptr)}};
}

std::string DatasetReportText(const DatasetReport& report) {
  std::string out;
  for (const DatasetProblem& p : report.problems) out += p.ToString() + "\n";
  if (!report.problems.empty()) {
    out += fmt::format("{} problem{} found\n\n", report.problems.size(),
                       report.problems.size() == 1 ? "" : "s");
  }
  if (report.dataset) {
    const SceneProfile profile = ProfileScene(*report.dataset);
    out += SummaryText(Summary(report, profile), profile);
  } else {
    out += "no summary: the transforms files could not be read far enough\n";
  }
  if (report.ok()) out += "ok: no problems\n";
  return out;
}

}  // namespace hdr4d
