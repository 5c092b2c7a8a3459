// hdr4d synth-ldr: LDR images from HDR through an exposure time and a camera response, for one
// image or for every frame of a dataset.
#include <fmt/format.h>

#include <filesystem>
#include <iostream>

#include "cli/commands.h"
#include "cli/flags.h"
#include "cli/pipeline_flags.h"
#include "core/radiometry/crf.h"
#include "core/util/error.h"
#include "core/radiometry/exposure_stack.h"
#include "core/image/image_io.h"
#include "core/radiometry/ldr_synthesis.h"
#include "core/files/output_guard.h"

namespace hdr4d::cli {
namespace fs = std::filesystem;

namespace {

struct SynthLdrArgs {
  std::string input;
  std::string output;
  std::string data;
  double exposure = 1.0;
  std::string crf = "filmic";
  double full_well = 0;
  double read_sigma = 0;
  std::uint64_t seed = 0;
  int bits = 8;
  bool keep_existing = false;
  bool overwrite = false;
  double gain_drift = 0;
  CameraPipelineOptions pipeline;
  ExposureUnit exposure_unit = ExposureUnit::kSeconds;  // of --data's scene
  bool exposure_unit_given = false;  // refused for one image (its --exposure is in seconds)
};

void Run(const SynthLdrArgs& a) {
  SensorNoise noise{.full_well = a.full_well, .read_sigma = a.read_sigma, .seed = a.seed};
  if (!a.data.empty()) {
    if (!a.input.empty() || !a.output.empty())
      Fail("synth-ldr: give either --data DIR or IN --out OUT, not both");
    DatasetSynthesisOptions options{.crf = a.crf,
                                    .noise = noise,
                                    .bits = a.bits,
                                    .overwrite = !a.keep_existing,
                                    .replace_foreign = a.overwrite,
                                    .gain_drift = a.gain_drift,
                                    .pipeline = a.pipeline,
                                    .exposure_unit = a.exposure_unit};
    options.pipeline.seed = a.seed;
    const int n = SynthesizeDatasetLdr(a.data, options);
    fmt::print(
        "synth-ldr: wrote {} LDR images in {} (camera response {}, settings in synthesis.json)\n",
        n, a.data, a.crf);
    return;
  }
  if (a.input.empty() || a.output.empty())
    Fail("synth-ldr: give IN and --out OUT, or --data DIR (see --help)");
  if (a.exposure_unit_given)
    Fail(
        "synth-ldr: --exposure-unit reads a scene's exposures (--data DIR); one image's "
        "--exposure is in seconds");
  if (!a.pipeline.IsIdentity())
    Fail("synth-ldr: --pipeline and --vignetting need --data DIR (a pipeline plans over the "
         "whole sequence)");
  LdrSynthesisOptions options{.exposure = a.exposure, .noise = noise, .bits = a.bits};
  options.Validate();
  const auto crf = ParseCrf(a.crf);
  // The input is never the output, whatever the spelling (a symlink, a hard link, ./x.exr).
  ProtectInputFile(a.input, "the input of synth-ldr");
  CheckOutputFile(a.output);
  const Image hdr = ReadImage(a.input);
  if (hdr.encoding() != Encoding::kLinear) {
    Fail("{}: expected a linear HDR image (EXR); this one is display-encoded", a.input);
  }
  Image ldr;
  try {
    ldr = SynthesizeLdr(hdr, *crf, options);
  } catch (const Error& e) {  // a pixel that is not a radiance: say in which file
    Fail("{}: {}", a.input, e.what());
  }
  PixelFormat format = PixelFormat::kUint8;
  if (a.bits == 16) format = PixelFormat::kUint16;
  if (a.bits == 0) format = PixelFormat::kFloat;
  WriteImage(a.output, ldr, {.format = format});
  fmt::print("synth-ldr: {} -> {} (exposure {} s, {})\n", a.input, a.output, a.exposure,
             crf->Spec());
}

}  // namespace

void AddSynthLdrCommand(CLI::App& app) {
  auto args = std::make_shared<SynthLdrArgs>();
  CLI::App* cmd = app.add_subcommand(
      "synth-ldr",
      "Synthesise LDR images from linear HDR: radiance x exposure time (+ sensor noise) -> camera "
      "response -> clip -> quantise.\n"
      "  One image:   hdr4d synth-ldr IN.exr --exposure 2 --out OUT.png\n"
      "  A dataset:   hdr4d synth-ldr --data SCENE   (every frame's file_path from its "
      "exr_file_path "
      "at its own `exposures` value)");
  cmd->add_option("input", args->input, "Linear HDR image (EXR) for single-image mode")
      ->check(Text("an HDR image"));
  cmd->add_option("--out,-o", args->output, "Output LDR image (.png, .jpg; .exr with --bits 0)")
      ->check(Text("an output image"));
  cmd->add_option("--data", args->data, "Dataset folder: synthesise every frame's LDR image")
      ->check(Text("a scene folder"));
  CLI::Option* unit = AddExposureUnitOption(cmd, &args->exposure_unit);
  cmd->add_option("--exposure,-e", args->exposure, "Exposure time in seconds (single-image mode)")
      ->check(PositiveReal())
      ->capture_default_str();
  cmd->add_option("--crf", args->crf,
                  "Camera response: linear, gamma:G, srgb, filmic[:contrast,mid], table:FILE.csv")
      ->check(Text("a camera response"))
      ->capture_default_str();
  cmd->add_option("--full-well", args->full_well,
                  "Shot noise: photo-electrons at saturation (0 = no shot noise)")
      ->check(Real(0, 1e12))
      ->capture_default_str();
  cmd->add_option("--read-noise", args->read_sigma, "Read noise std in units of full scale")
      ->check(Real(0, 1))
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "Noise seed (same seed, same bytes)")
      ->check(Seed())
      ->capture_default_str();
  cmd->add_option("--bits", args->bits, "Quantisation: 8, 16, or 0 for float output")
      ->check(OneOf({"0", "8", "16"}))
      ->capture_default_str();
  cmd->add_flag("--keep-existing", args->keep_existing, "Dataset mode: skip LDR images that exist");
  cmd->add_flag("--overwrite", args->overwrite,
                "Dataset mode: replace existing LDR images although the scene has no "
                "synthesis.json (synth-ldr did not make them); without it they are refused")
      ->excludes("--keep-existing");
  cmd->add_option("--gain-drift", args->gain_drift,
                  "Dataset mode: a hidden camera gain exp(D (t - 0.5)) over normalised time t "
                  "(auto-exposure-like; the JSON keeps the nominal exposures)")
      ->check(Real(-20, 20))
      ->capture_default_str();
  auto pipeline = std::make_shared<PipelineFlags>(cmd, args->pipeline);
  cmd->callback([args, pipeline, unit] {
    pipeline->Check();
    args->exposure_unit_given = unit->count() > 0;
    Run(*args);
  });
}

}  // namespace hdr4d::cli
