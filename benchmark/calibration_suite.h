// `hdr4d bench calibration`: `hdr4d calibrate` over a grid of synthetic capture variants and
// seeds (issue 54). Each variant x seed renders a capture with `hdr4d datagen --capture` (once:
// a capture already in the work folder is reused), calibrates it with `calibrate --truth`, and
// becomes one row of errors against the truth: registration, rotation (three ways, see
// calibration/truth_comparison.h), camera centres, focal length, the distortion terms kept, the
// fused HDR's log-log slope, median and darkest-fifth error, and the cameras' disagreement
// after gains. The grid is a JSON file (benchmark/suites/calibration.json; format in
// benchmark/suites/README.md); every key is checked.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace hdr4d::bench {

struct CalibrationVariant {
  std::string name;
  nlohmann::json datagen = nlohmann::json::object();    // over the grid's capture flags
  nlohmann::json calibrate = nlohmann::json::object();  // over the grid's calibrate flags
};

struct CalibrationGrid {
  std::string name, description, scene = "room", preset = "mini";
  std::filesystem::path file;
  nlohmann::json datagen = nlohmann::json::object(), calibrate = nlohmann::json::object();
  std::vector<int> seeds = {0};
  std::vector<CalibrationVariant> variants;
};

// Throws hdr4d::Error naming the file and key for an unknown key or a bad value.
CalibrationGrid ParseCalibrationGrid(const nlohmann::json& doc, const std::filesystem::path& file);
CalibrationGrid LoadCalibrationGrid(const std::filesystem::path& file);

// The targets; a row meets them all or names the ones it missed.
struct CalibrationTargets {
  double rotation_deg = 0.25, centre_relative = 0.005, focal_relative = 0.01;
  double slope_low = 0.95, slope_high = 1.05, camera_disagreement = 0.03;
};

struct CalibrationRow {
  std::string variant;
  int seed = 0;
  std::string failed;  // where it stopped ("datagen: ...", "calibrate: ..."), else empty
  std::string registration;  // "all cameras, extra 6/6, rung 1"
  double rotation_centres_deg = 0, rotation_oriented_deg = 0, rotation_pairs_deg = 0;
  double centre_relative = 0, focal_relative = 0;
  std::string distortion;  // per camera: "-", "k1" or "k1k2"
  double slope = 0, hdr_median = 0, hdr_dark = 0, camera_disagreement = 0;
  // The slope against the raw render and what a perfect calibration reads there (the resampling
  // of distorted cameras alone); -1 where the comparison predates them.
  double slope_render = -1, slope_render_floor = -1;
  double sparse_disagreement_after = 0;  // calibrate's, on its sparse points (texture included)
  double held_out_bias = 0;  // calibrate's gains checked on held-out points (no truth needed)
  // Vignetting: how many cameras had a falloff divided out, of how many had one in the truth,
  // and the largest |v divided out - v true| over the cameras (0 where nothing either side).
  int vignetting_corrected = 0, vignetting_true = 0;
  double vignetting_error = 0;
  double calibrate_seconds = 0;
  std::vector<std::string> missed;  // targets not met (empty: all met)
};

// One row from a finished variant folder (calibrated/ with truth_comparison.json and
// calibration.json, capture/<scene>/truth/cameras.json for the extra views). Throws
// hdr4d::Error naming the file when one is missing or malformed.
CalibrationRow ReadCalibrationRow(const std::filesystem::path& calibrated, const CalibrationTargets& targets);

std::string CalibrationTableMarkdown(const std::vector<CalibrationRow>& rows);
std::string CalibrationTableCsv(const std::vector<CalibrationRow>& rows);

struct CalibrationSuiteOptions {
  std::filesystem::path work;   // one folder per variant x seed
  std::vector<std::string> only;  // variant names; empty: all
  bool dry_run = false;          // list the commands, run nothing
  bool recalibrate = false;      // calibrate again even where a result exists (COLMAP's model reused)
  double timeout_minutes = 120;  // per command
};

// Runs the grid (one command at a time) and writes calibration_table.{md,csv} into `work`;
// returns the rows. A variant that fails is a row saying where; the grid goes on.
std::vector<CalibrationRow> RunCalibrationSuite(const CalibrationGrid& grid, const CalibrationSuiteOptions& options);

}  // namespace hdr4d::bench
