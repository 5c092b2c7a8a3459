// `hdr4d dataset check DIR`: every problem of a scene, then what the scene is.
#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "cli/commands.h"
#include "cli/flags.h"
#include "core/dataset/dataset.h"
#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/files/json_util.h"
#include "core/dataset/scene_profile.h"
#include "core/viz/preview.h"

namespace hdr4d::cli {
namespace {

struct CheckArgs {
  std::string dir;
  bool json = false;
  bool full = false;
  bool reference_time = false;
};

const char* HdrGroundTruth(const SceneProfile& profile) {
  return profile.has_hdr_gt ? "yes" : profile.partial_hdr_gt ? "partial" : "no";
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
  std::string exposures;
  for (double e : profile.exposures)
    exposures += (exposures.empty() ? "" : ", ") + fmt::format("{:g}", e);
  line(fmt::format("  exposures:   {} distinct ({} s)", profile.exposures.size(), exposures));
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

int RunCheck(const CheckArgs& args) {
  DatasetLoadOptions options;
  options.image_check = args.full ? ImageCheck::kFull : ImageCheck::kHeaders;
  options.time_normalisation =
      args.reference_time ? TimeNormalisation::kPerFileReference : TimeNormalisation::kGlobal;
  options.show_progress = true;
  const DatasetReport report = CheckDataset(args.dir, options);

  std::optional<SceneProfile> profile;
  nlohmann::json summary = nullptr;
  if (report.dataset) {
    profile = ProfileScene(*report.dataset);
    summary = Summary(report, *profile);
  }

  if (args.json) {
    nlohmann::json problems = nlohmann::json::array();
    for (const DatasetProblem& p : report.problems) {
      problems.push_back({{"file", p.file.string()},
                          {"frame", p.frame},
                          {"key", p.key},
                          {"message", p.message},
                          {"text", p.ToString()}});
    }
    const nlohmann::json out = {{"ok", report.ok()},
                                {"problems", problems},
                                {"summary", summary},
                                {"profile", profile ? profile->ToJson() : nlohmann::json(nullptr)}};
    std::fputs((out.dump(1) + "\n").c_str(), stdout);
  } else {
    for (const DatasetProblem& p : report.problems)
      std::fputs((p.ToString() + "\n").c_str(), stdout);
    if (!report.problems.empty()) {
      std::fputs(fmt::format("{} problem{} found\n\n", report.problems.size(),
                             report.problems.size() == 1 ? "" : "s")
                     .c_str(),
                 stdout);
    }
    if (profile) {
      std::fputs(SummaryText(summary, *profile).c_str(), stdout);
    } else {
      std::fputs("no summary: the transforms files could not be read far enough\n", stdout);
    }
    if (report.ok()) std::fputs("ok: no problems\n", stdout);
  }
  std::fflush(stdout);
  return report.ok() ? 0 : 1;
}

}  // namespace

namespace {

struct PreviewArgs {
  std::string dir;
  std::string out;
  PreviewOptions options;
};

void RunPreview(const PreviewArgs& args) {
  const Dataset dataset =
      LoadDataset(args.dir, {.image_check = ImageCheck::kHeaders, .require_test = false});
  const Preview preview = MakeDatasetPreview(dataset, args.options);
  WriteImage(args.out, preview.sheet);
  fmt::print("preview: {} ({} rows x {} timestamps)\n", args.out, preview.row_labels.size(),
             preview.column_times.size());
  for (std::size_t r = 0; r < preview.row_labels.size(); ++r)
    fmt::print("  row {}: {}\n", r + 1, preview.row_labels[r]);
  std::string times;
  for (double t : preview.column_times)
    times += fmt::format("{}{:.3g}", times.empty() ? "" : ", ", t);
  fmt::print("  columns: t = {}\n", times);
}

}  // namespace

void AddDatasetCommand(CLI::App& app) {
  CLI::App* dataset =
      app.add_subcommand("dataset", "Inspect scenes in the dataset format (ARCHITECTURE §3)");
  // `hdr4d dataset` alone: one line naming the subcommands, like every other usage mistake.
  dataset->require_subcommand(0, 1);
  dataset->callback([dataset] {
    if (!dataset->get_subcommands().empty()) return;
    Fail("dataset: a subcommand is required: check or preview (see `hdr4d dataset --help`)");
  });

  auto args = std::make_shared<CheckArgs>();  // dataset check
  CLI::App* check =
      dataset->add_subcommand("check", "Report every problem of a scene, then summarise it");
  check->footer(
      "Prints one line per problem (file: frame N: key: message), then a summary: layout, "
      "frames per split, cameras, exposures, time span, HDR ground truth, resolution, point "
      "cloud and the scene profile (what later stages skip).\nExit code 0 when the scene has no "
      "problem, 1 when it has one (the report is printed either way).");
  check->add_option("DIR", args->dir, "Scene folder (transforms_{train,test}.json at its root)")
      ->required()
      ->check(Text("a scene folder"));
  check->add_flag(
      "--json", args->json,
      "Print the report as JSON: {ok, problems: [...], summary: {...}, profile: {...}}");
  check->add_flag("--full", args->full,
                  "Decode every image (finds corrupt pixel data and NaN/Inf in EXR); default reads "
                  "headers only");
  check->add_flag("--reference-time", args->reference_time,
                  "Normalise times per JSON file by its own maximum, as the reference code does "
                  "(default: by the maximum over all splits)");
  check->callback([args] {
    const int code = RunCheck(*args);
    if (code != 0) throw CLI::RuntimeError(code);
  });

  auto preview_args = std::make_shared<PreviewArgs>();
  CLI::App* preview = dataset->add_subcommand(
      "preview",
      "Write a contact sheet of one camera over time: a row per exposure, then the HDR truth");
  preview->add_option("DIR", preview_args->dir, "Scene folder")
      ->required()
      ->check(Text("a scene folder"));
  preview->add_option("--out,-o", preview_args->out, "Output image (.png)")
      ->required()
      ->check(Text("an output image"));
  preview->add_option("--split", preview_args->options.split, "train, test or val")
      ->check(OneOf({"train", "test", "val"}))
      ->capture_default_str();
  preview
      ->add_option("--camera", preview_args->options.camera_id,
                   "camera_id to show (-1: the split's first)")
      ->check(Integer(-1))
      ->capture_default_str();
  preview
      ->add_option("--columns", preview_args->options.max_columns,
                   "Timestamps shown, evenly sampled")
      ->check(Integer(1, 1000))
      ->capture_default_str();
  preview->callback([preview_args] { RunPreview(*preview_args); });
}

}  // namespace hdr4d::cli
