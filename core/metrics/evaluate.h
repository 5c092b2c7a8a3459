// `hdr4d eval`: score predicted images against ground truth, file by file or folder by folder
// (ARCHITECTURE §5). The result is one JSON document:
//
//   {"pairs": [{"name": <gt file name>, <metric>: <value>, ...}, ...],
//    "mean":  {<metric>: <value>, ...}, "identical_pairs": <count>}
//
// - LDR pairs (both integer formats such as PNG/JPEG, read as display-encoded values) get the
//   LdrMetrics keys, computed on the stored sRGB values as the reference code does: "psnr",
//   "psnr_channel_mean", "ssim", then "flip" (LDR-FLIP, core/metrics/flip.h: the mean of the
//   per-pixel error, lower is better, as NVIDIA's FLIP tool reports it).
// - HDR pairs (both float formats: EXR, Radiance .hdr) get the HdrMetrics keys: "mu_psnr",
//   "mu_ssim" (own-max normalisation), "mu_psnr_gt_max", "mu_ssim_gt_max", "pu21_psnr",
//   "pu21_ssim", "hdr_flip" (HDR-FLIP with the tool's defaults: ACES, the exposure range from
//   the ground truth), then the AlignedHdrMetrics keys (core/metrics/hdr_alignment.h): "hdr_align_scale",
//   "hdr_log_slope", "hdr_log_corr", "hdr_log_contrast", "hdr_measured_fraction",
//   "mu_psnr_aligned", "mu_ssim_aligned", "pu21_psnr_aligned", "pu21_ssim_aligned". Their
//   pixels are those an LDR bracket of the view measures when the brackets are known
//   (EvalBrackets), else every pixel with positive luminance in both images. When the brackets
//   are known, `ldr_fit` is set and the prediction's folder holds renders named like some of
//   them at their exposures (as `hdr4d render` writes them without --exposure), also the
//   LdrFitHdrShape keys: "hdr_log_slope_ldr_fit", "hdr_log_corr_ldr_fit",
//   "hdr_ldr_fit_fraction" (the HDR's shape where those renders reproduce their bracket; a
//   render that cannot be read is an error naming it; `ldr_fit` because only the caller knows
//   that the renders are at their brackets' exposures). A key whose value
//   is undefined for a pair (the log-log slope of an image with one measured pixel, or of a
//   constant truth) is left out of that pair's numbers and listed with its reason under the
//   pair's "undefined" object (null stays reserved for +inf).
// - Pairs are listed in sorted order of the ground-truth file name. "mean" is the arithmetic mean
//   of the per-pair values of each key over the pairs that have the key (not a metric of the
//   pooled error), except "hdr_log_slope_ldr_fit" and "hdr_log_corr_ldr_fit", which are pooled
//   within images (PoolLogShape: a view with a narrow range of measured truth would swing a mean
//   of slopes).
// - Non-finite numbers are written as null (identical images have PSNR +inf). "mean" is over the
//   finite values of each key (null when there is none), so one identical pair does not hide
//   the others; "identical_pairs" counts the pairs whose images are equal.
#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/dataset/dataset.h"

namespace hdr4d {

// The LDR brackets of HDR ground-truth images: ground-truth resolved path (or, in a hand-made
// map, file name) -> the LDR images of the same view at its exposures.
using EvalBrackets = std::map<std::string, std::vector<std::filesystem::path>>;

// The brackets of every frame of the dataset at `scene` with an exr_file_path (all splits),
// keyed by the HDR file's resolved path. Throws hdr4d::Error when the dataset cannot be read.
// `unit`: how the scene's exposures are read (its --exposure-unit).
EvalBrackets DatasetBrackets(const std::filesystem::path& scene,
                             ExposureUnit unit = ExposureUnit::kSeconds);

// One pair of image files: {"name": <gt file name>, <metric>: <value or null>, ...}. Throws
// hdr4d::Error naming both files for a missing/unreadable image, an LDR file paired with an HDR
// one, different sizes or channel counts, or an HDR image that cannot be normalised.
// gt_resolution R > 1: the ground truth (and its brackets) reduced as `hdr4d train
// --resolution R` reduces its targets (R x R box average, LDR quantised to 8 bits), to score the
// renders of such a run; an R that does not divide a ground truth is an error naming it.
nlohmann::json EvaluatePair(const std::filesystem::path& pred,
                            const std::filesystem::path& gt,
                            const EvalBrackets* brackets = nullptr,
                            int gt_resolution = 1);

// `pred` and `gt` are both image files (one pair) or both folders. Folders: every image in the
// pred folder and its sub-folders (non-image files are ignored) is paired with the ground truth
// at the same path inside the gt folder (`cam0/x.png` with `cam0/x.png`, as `hdr4d render` keeps
// a dataset's sub-folders), or else with the one ground truth of the same path and stem whose
// extension is of the same kind (LDR with LDR, EXR/HDR with EXR/HDR); a pair's "name" is that
// path. Ground-truth images without a prediction
// are skipped with a warning (a dataset's image folder holds every split). A prediction without
// ground truth, an empty pred folder, or a file paired with a folder throws hdr4d::Error naming
// what is missing. Pairs are evaluated in parallel; the output
// does not depend on the thread count.
nlohmann::json EvaluatePaths(const std::filesystem::path& pred,
                             const std::filesystem::path& gt,
                             const EvalBrackets* brackets = nullptr,
                             int gt_resolution = 1,
                             bool ldr_fit = false);

// A fixed-width text table of an EvaluatePaths result: a header, one line per pair, a "mean"
// line. A null (non-finite) value is shown as "inf", a key a pair does not have as "-".
std::string FormatEvalTable(const nlohmann::json& result);

}  // namespace hdr4d
