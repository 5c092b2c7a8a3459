// hdr4d calibrate: a fixed multi-camera rig with bracketed exposures, calibrated into a dataset.
#include <fmt/format.h>

#include <filesystem>

#include "calibration/calibrate.h"
#include "calibration/truth_comparison.h"
#include "cli/commands.h"
#include "cli/flags.h"
#include "core/files/json_util.h"
#include "core/util/error.h"

namespace hdr4d::cli {

namespace {

// Where the rig's geometry comes from: a checkerboard, COLMAP's binary and image size.
void AddGeometryFlags(CLI::App* cmd, CalibrateOptions* options) {
  cmd->add_option("--board", options->board,
                  "A checkerboard in static/: <cols>x<rows>:<square metres> (inner corners), for "
                  "intrinsics and the metric scale")
      ->check(Text("a board spec"));
  cmd->add_option("--colmap-binary", options->colmap_binary, "COLMAP executable")
      ->capture_default_str()
      ->check(Text("an executable"));
  cmd->add_option("--colmap-max-image-size", options->colmap_max_image_size,
                  "Downscale images to this size for COLMAP's SIFT (0: COLMAP's default, 3200)")
      ->check(Integer(0, 100000));
  cmd->add_flag("--focal-multistart,!--no-focal-multistart", options->focal_multistart,
                "Once the models are chosen, restart the rig refinement from COLMAP's poses and focal "
                "lengths x0.96 to x1.04 (steps of 0.01) and keep the least robust cost: a rig camera seen "
                "in one pose has shallow minima about 1% of focal apart (on by default)");
  cmd->add_flag("--rig-time-points", options->rig_time_points,
                "Also match the rig cameras with one another at every time of the sequence (SIFT on "
                "one mid bracket each) and add the triangulated points to the rig refinement: more "
                "observations for the focal lengths and distortion where there are no hand-held views");
}

// The response recovery and how the cameras' curves are fused.
void AddRadiometryFlags(CLI::App* cmd, CalibrateOptions* options) {
  cmd->add_option("--samples", options->response.samples, "Pixels sampled for the response")
      ->capture_default_str()
      ->check(Integer(2, 10000000));
  cmd->add_flag("--robertson", options->response.robertson,
                "Recover the response with Robertson et al. instead of Debevec-Malik");
  cmd->add_flag(
      "--per-camera-response", options->per_camera_response,
      "Fuse each camera with its own response curve (default: only when the cameras' curves "
      "differ by more than 0.05 RMS in log exposure)");
  cmd->add_option("--gain-footprint", options->gain_footprint_pixels,
                  "Unlike cameras' gains compare the same patch of surface around each sparse point: "
                  "a disc of this radius in pixels in the camera that sees it smallest, larger in the "
                  "others (0: a 3x3 window in every camera)")
      ->capture_default_str()
      ->check(Real(0, 100));
  cmd->add_option_function<std::string>(
         "--vignetting", [options](const std::string& text) { options->vignetting = ParseVignettingCorrection(text); },
         "Each rig camera's vignetting (radiance x 1 - v (r / r_corner)^2) is estimated from the points the "
         "cameras share; auto: divided out of its HDR and brackets where v >= 0.05 and at least 4 standard "
         "errors (the brackets are then "
         "re-encoded through the response as 16-bit PNG); on: every camera's estimate; off: reported only")
      ->default_str("auto")
      ->check(CLI::IsMember({"auto", "on", "off"}));
  cmd->add_option("--smoothness", options->response.smoothness, "Debevec-Malik smoothness weight")
      ->capture_default_str()
      ->check(Real(0, 1e9));
}

// The lens model: undistortion, shared intrinsics, which distortion terms are kept.
void AddLensFlags(CLI::App* cmd, CalibrateOptions* options, bool* keep_distortion, bool* no_refinement,
                  bool* separate_focal) {
  cmd->add_option("--undistort-threshold", options->undistort_threshold_pixels,
                  "Undistort images when lens distortion moves a pixel by more than this")
      ->capture_default_str()
      ->check(Real(0, 1e6));
  cmd->add_flag(
      "--shared-intrinsics", options->shared_intrinsics,
      "Rig cameras of the same image size are one model: they share focal length and distortion");
  cmd->add_flag(
      "--keep-distortion", *keep_distortion,
      "Keep COLMAP's k1, k2 for every camera (default: only where they explain the observations "
      "beyond noise, by BIC; a distortion-free lens is then not resampled)");
  cmd->add_flag(
      "--separate-focal", *separate_focal,
      "Each camera its own focal length (default: cameras of one image size share one where that "
      "explains the observations as well, by BIC: one model of camera)");
  cmd->add_flag("--no-refinement", *no_refinement,
                "Keep COLMAP's poses, intrinsics and points as they are (no Ceres refinement, no "
                "distortion selection): to see what the refinement changes");
}

// --truth: the calibrated dataset against a synthetic capture's truth, printed and written.
void ReportAgainstTruth(const std::string& out, const std::string& truth) {
  const TruthComparison comparison = CompareWithTruth(out, truth);
  const std::string md = TruthComparisonMarkdown(comparison);
  WriteJsonFile(std::filesystem::path(out) / "truth_comparison.json",
                TruthComparisonJson(comparison));
  WriteTextFileAtomic(std::filesystem::path(out) / "truth_comparison.md",
                      "# Calibration against the truth of " + truth + "\n\n" + md);
  fmt::print("calibrate: against the truth of {}:\n{}", truth, md);
}

}  // namespace

void AddCalibrateCommand(CLI::App& app) {
  auto options = std::make_shared<CalibrateOptions>();
  auto capture = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto colmap_model = std::make_shared<std::string>();
  auto stage = std::make_shared<std::string>("all");
  auto no_motion = std::make_shared<bool>(false);
  auto no_gains = std::make_shared<bool>(false);
  auto keep_distortion = std::make_shared<bool>(false);
  auto no_refinement = std::make_shared<bool>(false);
  auto separate_focal = std::make_shared<bool>(false);
  auto truth = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate",
      "Turn a capture of a fixed camera rig with bracketed exposures (static/<camera>/, "
      "sequence/<camera>/<frame>_<k>.<ext>, optional exposures.json) into a dataset: COLMAP + "
      "Ceres rig geometry, Debevec-Malik response, fused HDR ground truth, report.md.");
  cmd->add_option("--capture", *capture, "Capture folder")
      ->required()
      ->check(Text("a capture folder"));
  cmd->add_option("--out,-o", *out, "Output dataset folder")
      ->required()
      ->check(Text("an output folder"));
  cmd->add_option(
         "--colmap-model", *colmap_model,
         "Reuse this COLMAP sparse model (image names <camera>/<file>) instead of running COLMAP")
      ->check(Text("a COLMAP sparse model folder"));
  cmd->add_option("--stage", *stage, "geometry, radiometry or all")
      ->capture_default_str()
      ->check(OneOf({"geometry", "radiometry", "all"}));
  cmd->add_option("--fps", options->fps, "Frames per second (time = frame index / fps)")
      ->capture_default_str()
      ->check(PositiveReal(1e6));
  cmd->add_option("--test-camera", options->test_camera, "Held-out camera (default: the last one)")
      ->check(Text("a camera name"));
  AddGeometryFlags(cmd, options.get());
  AddRadiometryFlags(cmd, options.get());
  AddLensFlags(cmd, options.get(), keep_distortion.get(), no_refinement.get(), separate_focal.get());
  cmd->add_flag("--no-motion-detection", *no_motion,
                "Average every bracket even where they disagree");
  cmd->add_option("--truth", *truth,
                  "The truth/ folder of a synthetic capture (hdr4d datagen --capture): after "
                  "calibrating, compare poses (after a similarity), focal lengths, the response "
                  "and the fused HDR with it; prints a table, writes truth_comparison.{json,md}")
      ->check(Text("a truth folder"));
  cmd->add_flag("--no-gain-correction", *no_gains,
                "Measure the cameras' disagreement but leave their HDR and exposures as fused");
  cmd->callback([=] {
    options->correct_gains = !*no_gains;
    options->select_distortion = !*keep_distortion;
    options->refine_rig = !*no_refinement;
    options->select_shared_focal = !*separate_focal;
    options->capture = *capture;
    options->out = *out;
    if (!colmap_model->empty()) options->colmap_model = *colmap_model;
    options->stage = ParseCalibrationStage(*stage);
    options->fusion.detect_motion = !*no_motion;
    // A truth folder that cannot be read fails before the calibration, not after it.
    if (!truth->empty() &&
        !std::filesystem::is_regular_file(std::filesystem::path(*truth) / "cameras.json"))
      Fail(
          "{}: --truth needs the truth/ folder of `hdr4d datagen --capture` (no cameras.json in "
          "it)",
          *truth);
    const CalibrateSummary s = Calibrate(*options);
    fmt::print(
        "calibrate: {} cameras, {} frames, {} images written{} to {} (geometry {:.1f} s, "
        "radiometry {:.1f} s); see {}/report.md\n",
        s.cameras, s.frames, s.images_written, s.dataset_written ? ", dataset" : "", *out,
        s.seconds_geometry, s.seconds_radiometry, *out);
    if (!truth->empty()) ReportAgainstTruth(*out, *truth);
  });
}

}  // namespace hdr4d::cli
