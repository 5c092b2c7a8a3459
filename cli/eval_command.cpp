// `hdr4d eval PRED GT [--json] [--out FILE]`: image metrics of predictions against ground truth.
#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <string>

#include "cli/commands.h"
#include "cli/flags.h"
#include "core/metrics/evaluate.h"
#include "core/util/error.h"
#include "core/files/json_util.h"
#include "core/files/output_guard.h"
#include "core/util/error.h"

namespace hdr4d::cli {

namespace {

struct EvalOptions {
  std::string pred;
  std::string gt;
  bool json = false;
  std::string out;
  std::string data;
  ExposureUnit exposure_unit = ExposureUnit::kSeconds;  // of --data
  bool ldr_fit = false;
  int resolution = 1;
};

constexpr const char* kEvalFooter = R"(
Matching: PRED and GT are two image files or two folders. In folders, every image in PRED is
paired with the ground truth of the same file name; failing that, with the one ground truth of
the same stem and an extension of the same kind (r_001.jpg for r_001.png, r_001.hdr for
r_001.exr). A prediction without ground truth is an error; ground-truth images without a
prediction (another split's, in a dataset's image folder) are skipped with a warning;
non-image files are ignored.

LDR pairs (PNG/JPEG/...; both integer) are scored on the stored sRGB values:
  psnr               10 log10(1/MSE), MSE over all pixels and RGB channels
  psnr_channel_mean  PSNR per channel, then the mean (what the 3DGS/4DGS code reports)
  ssim               11x11 Gaussian window, sigma 1.5, zero padding, per channel (3DGS)
  flip               LDR-FLIP (Andersson et al. 2020), mean per-pixel error in [0,1], lower
                     is better; 67 pixels per degree; matches NVIDIA's FLIP tool
HDR pairs (EXR/HDR; both float) are scored with:
  mu_psnr, mu_ssim   HDR-4DGS protocol: prediction / its own max, clamped to [0,1];
                     ground truth / its own max; mu-law log(1+5000x)/log(5001); PSNR, SSIM
  mu_*_gt_max        HDR-NeRF protocol: both divided by the ground truth's max
  pu21_psnr          PU21 (banding_glare) of every RGB value, peak 256 (~100 cd/m^2)
  pu21_ssim          SSIM on PU21 luminance, C1 = (0.01*256)^2, C2 = (0.03*256)^2
  hdr_flip           HDR-FLIP (Andersson et al. 2021): the worst LDR-FLIP per pixel over
                     ACES-tone-mapped exposures whose range comes from the ground truth
                     (NVIDIA's tool's figure; not scale-free)
PU21 scaling: both images are multiplied by 4000 / (max luminance of the ground truth),
luminance = 0.212656 R + 0.715158 G + 0.072186 B, then clamped to [0.005, 10000] cd/m^2.
Scale-aligned HDR metrics (LDR fixes an HDR only up to one factor, and cannot tell how bright
a light is that clips at every exposure; the own-max protocol divides by exactly that guess):
  measured pixels    with --data SCENE: pixels that some LDR bracket of the view (the
                     frames sharing its exr_file_path) records unclipped and above black;
                     without: pixels of positive luminance in both images
  hdr_align_scale    exp(median over measured pixels of log Y_gt - log Y_pred), Y = luminance
  hdr_log_slope      least-squares slope of log Y_pred on log Y_gt over the measured pixels
                     (1: the truth's shape; 0.25: the truth to the power 0.25)
  hdr_log_corr       their Pearson correlation
  hdr_log_contrast   std(log Y_pred) / std(log Y_gt) over the same pixels: the HDR's shape
                     without the pull of misplaced pixels (slope = corr x contrast; on a
                     held-out view, geometry errors lower corr and with it the slope)
  hdr_measured_fraction  measured pixels / all pixels
  hdr_log_slope_ldr_fit, hdr_log_corr_ldr_fit
                     with --data SCENE --ldr-fit and the LDR renders of the brackets in the
                     prediction's folder (as hdr4d render writes them): slope and correlation
                     over the measured pixels that a rendered bracket reproduces (in a bracket
                     where the truth's brightest channel is >= 0.15, every channel of the
                     render within 10% of that value). The geometry is right there, so this
                     is the tone curve's shape: a squeezed HDR behind a right LDR keeps its low
                     slope, misplaced pixels drop out
  hdr_ldr_fit_fraction   those pixels / the measured pixels
                     In "mean" the two shape keys are pooled within images (the sums about
                     each image's own means added), not means of per-image values: one image
                     with a narrow range of reproduced truth would swing a mean of slopes
  mu_*_aligned       prediction times hdr_align_scale, then the HDR-NeRF (GT max) protocol
  pu21_*_aligned     prediction times hdr_align_scale, then PU21 as above
  hdr_flip_aligned   prediction times hdr_align_scale, then HDR-FLIP as above (the
                     tables' HDR FLIP)
Metrics use the first three channels (alpha is ignored). "mean" is the mean of the
per-image values that are finite. Identical images have PSNR inf, written as null in JSON and
left out of the means; "identical_pairs" counts them.)";

}  // namespace

void AddEvalCommand(CLI::App& app) {
  auto options = std::make_shared<EvalOptions>();
  CLI::App* sub = app.add_subcommand(
      "eval", "Score predicted images against ground truth (PSNR, SSIM; mu-law and PU21 for HDR)");
  sub->add_option("PRED", options->pred, "Predicted image, or a folder of them")
      ->required()
      ->check(Text("an image or a folder"));
  sub->add_option("GT", options->gt, "Ground-truth image, or a folder of them")
      ->required()
      ->check(Text("an image or a folder"));
  sub->add_flag("--json", options->json, "Print the result as JSON instead of a table");
  sub->add_option("--out", options->out, "Also write the JSON result to this file")
      ->check(Text("an output file"));
  sub->add_option("--data", options->data,
                  "Scene of the HDR ground truth: its LDR brackets decide the measured pixels of "
                  "the aligned HDR metrics")
      ->check(Text("a dataset folder"));
  AddExposureUnitOption(sub, &options->exposure_unit);
  sub->add_flag("--ldr-fit", options->ldr_fit,
                "With --data: the prediction folder's LDR images are renders of the brackets at "
                "their own exposures (hdr4d render without --exposure); adds the HDR's shape "
                "where they reproduce the brackets (hdr_log_slope_ldr_fit, see below)");
  sub->add_option("--resolution", options->resolution,
                  "Reduce the ground truth R times (R x R box average) first, as `hdr4d train "
                  "--resolution R` reduced its targets: scores the renders of such a run")
      ->check(Integer(1, 1 << 16))
      ->capture_default_str();
  sub->footer(kEvalFooter);
  sub->callback([options] {
    // The images scored are inputs: --out may not replace them or land among them, and that is
    // known before any image is read.
    ProtectInput(options->pred, "the predictions eval scores");
    ProtectInput(options->gt, "the ground truth eval scores against");
    if (!options->out.empty()) CheckOutputFile(options->out);
    if (options->ldr_fit && options->data.empty())
      Fail("eval: --ldr-fit needs --data SCENE (the LDR brackets the renders are compared with)");
    EvalBrackets brackets;
    if (!options->data.empty()) brackets = DatasetBrackets(options->data, options->exposure_unit);
    const nlohmann::json result =
        EvaluatePaths(options->pred, options->gt, options->data.empty() ? nullptr : &brackets,
                      options->resolution, options->ldr_fit);
    if (!options->out.empty()) WriteJsonFile(options->out, result);
    if (options->json) {
      fmt::print("{}\n", result.dump(1));
    } else {
      fmt::print("{}", FormatEvalTable(result));
    }
  });
}

}  // namespace hdr4d::cli
