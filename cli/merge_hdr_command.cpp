// hdr4d merge-hdr: classic multi-exposure fusion of a dataset's frames with a known response.
#include <fmt/format.h>

#include "cli/commands.h"
#include "cli/flags.h"
#include "core/radiometry/exposure_stack.h"

namespace hdr4d::cli {

void AddMergeHdrCommand(CLI::App& app) {
  auto options = std::make_shared<MergeOptions>();
  auto data = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "merge-hdr",
      "Merge the LDR frames that share a view and a time (several exposures) into one HDR image "
      "with the known camera response (Debevec-Malik weighted average). Outputs are named like "
      "the frames' exr_file_path, so `hdr4d eval OUT SCENE/hdr` scores them.");
  cmd->add_option("--data", *data, "Dataset folder")->required()->check(Text("a scene folder"));
  cmd->add_option("--out,-o", *out, "Output folder for the merged EXR images")
      ->required()
      ->check(Text("an output folder"));
  cmd->add_option("--crf", options->crf,
                  "Camera response (default: the one in DATA/synthesis.json)")
      ->check(Text("a camera response"));
  cmd->add_option("--split", options->split, "train, test, val or all")
      ->check(OneOf({"train", "test", "val", "all"}))
      ->capture_default_str();
  cmd->add_flag("--overwrite", options->overwrite,
                "Replace merged images already in --out (else a file there of an output's name is "
                "an error, before anything is written)");
  AddExposureUnitOption(cmd, &options->exposure_unit);
  cmd->callback([options, data, out] {
    const int n = MergeDatasetExposures(*data, *out, *options);
    fmt::print("merge-hdr: wrote {} HDR images to {}\n", n, *out);
  });
}

}  // namespace hdr4d::cli
