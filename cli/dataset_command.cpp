// `hdr4d dataset check DIR`: every problem of a scene, then what the scene is
// (core/dataset/dataset_check_report.h); `hdr4d dataset preview DIR`: a contact sheet;
// `hdr4d dataset split-val DIR --out NEW`: the scene with a val split (core/dataset/val_split.h).
#include <fmt/format.h>

#include <cstdio>
#include <memory>
#include <string>

#include "cli/commands.h"
#include "cli/flags.h"
#include "core/dataset/dataset.h"
#include "core/dataset/dataset_check_report.h"
#include "core/dataset/val_split.h"
#include "core/image/image_io.h"
#include "core/util/error.h"
#include "core/viz/preview.h"

namespace hdr4d::cli {
namespace {

struct CheckArgs {
  std::string dir;
  bool json = false;
  bool full = false;
  bool reference_time = false;
  ExposureUnit exposure_unit = ExposureUnit::kSeconds;
};

int RunCheck(const CheckArgs& args) {
  DatasetLoadOptions options;
  options.image_check = args.full ? ImageCheck::kFull : ImageCheck::kHeaders;
  options.time_normalisation =
      args.reference_time ? TimeNormalisation::kPerFileReference : TimeNormalisation::kGlobal;
  options.exposure_unit = args.exposure_unit;
  options.show_progress = true;
  const DatasetReport report = CheckDataset(args.dir, options);
  const std::string out =
      args.json ? DatasetReportJson(report).dump(1) + "\n" : DatasetReportText(report);
  std::fputs(out.c_str(), stdout);
  std::fflush(stdout);
  return report.ok() ? 0 : 1;
}

struct PreviewArgs {
  std::string dir;
  std::string out;
  PreviewOptions options;
  ExposureUnit exposure_unit = ExposureUnit::kSeconds;
};

void RunPreview(const PreviewArgs& args) {
  const Dataset dataset = LoadDataset(args.dir, {.image_check = ImageCheck::kHeaders,
                                                 .exposure_unit = args.exposure_unit,
                                                 .require_test = false});
  const Preview preview = MakeDatasetPreview(dataset, args.options);
  WriteImage(args.out, preview.sheet);
  fmt::print("{}", DescribePreview(preview, args.out));
}

void AddCheck(CLI::App* dataset) {
  auto args = std::make_shared<CheckArgs>();
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
  AddExposureUnitOption(check, &args->exposure_unit);
  check->callback([args] {
    const int code = RunCheck(*args);
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

void AddPreview(CLI::App* dataset) {
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
  AddExposureUnitOption(preview, &preview_args->exposure_unit);
  preview->callback([preview_args] { RunPreview(*preview_args); });
}

struct SplitValArgs {
  std::string dir;
  std::string out;
  ValSplitOptions options;
};

void AddSplitVal(CLI::App* dataset) {
  auto args = std::make_shared<SplitValArgs>();
  CLI::App* split = dataset->add_subcommand(
      "split-val",
      "Write a copy of a scene with some training frames moved to a val split, so that `hdr4d "
      "train` stops when those held-out views stop improving (the default where a scene has a "
      "val split)");
  split->footer(
      "The new scene holds its own transforms files and links to the original's images, HDR and "
      "point cloud; the original is not changed. Monocular captures: --every-time 8 holds back "
      "one frame in eight; fixed rigs: --camera ID holds back one camera (or --every-time K, "
      "one time in K on every camera); a static capture of separate views (one exposure each): "
      "--every-frame K holds back one view in K. A nerfstudio scene (one transforms.json) gets "
      "a copy of that file with val_filenames.");
  split
      ->add_option("DIR", args->dir,
                   "Scene folder (transforms_{train,test}.json, or nerfstudio's transforms.json, "
                   "at its root)")
      ->required()
      ->check(Text("a scene folder"));
  split->add_option("--out,-o", args->out, "The new scene folder (new, or empty)")
      ->required()
      ->check(Text("an output folder"));
  CLI::Option* every = split->add_option(
      "--every-time", args->options.every_time,
      "Move every frame of one training time in K (the middle time of each run of K) to val");
  every->check(Integer(2, 1000000));
  CLI::Option* camera = split
                            ->add_option("--camera", args->options.camera_id,
                                         "Move every training frame of this camera_id to val")
                            ->check(Integer(0))
                            ->excludes(every);
  split
      ->add_option("--every-frame", args->options.every_frame,
                   "Move every K-th training frame in file order (the middle one of each run of "
                   "K) to val: for a static capture whose frames are separate views")
      ->check(Integer(2, 1000000))
      ->excludes(every)
      ->excludes(camera);
  split->callback([args] {
    const ValSplitSummary s = SplitOffVal(args->dir, args->out, args->options);
    fmt::print("dataset split-val: wrote {} from {}: {} training frames moved to val ({}), {} "
               "left to train on\n",
               args->out, args->dir, s.moved, s.what, s.kept);
  });
}

}  // namespace

void AddDatasetCommand(CLI::App& app) {
  CLI::App* dataset =
      app.add_subcommand("dataset", "Inspect scenes in the dataset format (ARCHITECTURE §3)");
  // `hdr4d dataset` alone: one line naming the subcommands, like every other usage mistake.
  dataset->require_subcommand(0, 1);
  dataset->callback([dataset] {
    if (!dataset->get_subcommands().empty()) return;
    Fail("dataset: a subcommand is required: check, preview or split-val (see `hdr4d dataset "
         "--help`)");
  });
  AddCheck(dataset);
  AddPreview(dataset);
  AddSplitVal(dataset);
}

}  // namespace hdr4d::cli
