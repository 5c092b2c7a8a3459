#include "benchmark/calibration_suite.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <regex>

#include "benchmark/child_process.h"
#include "benchmark/settings_flags.h"
#include "core/files/atomic_file.h"
#include "core/files/json_util.h"
#include "core/util/error.h"

namespace hdr4d::bench {
namespace fs = std::filesystem;
namespace {

// The flags the suite sets itself from its axes: a grid may not.
const std::vector<std::string> kCalibrationReservedDatagen = {"capture", "scene", "preset", "seed", "out"};
const std::vector<std::string> kCalibrationReservedCalibrate = {"capture", "out", "truth", "colmap-model"};

void CalibrationOnlyKeys(const nlohmann::json& j, const std::string& where, const std::vector<std::string>& keys) {
  if (!j.is_object()) Fail("{}: expected a JSON object", where);
  for (const auto& item : j.items())
    if (item.key() != "comment" && std::find(keys.begin(), keys.end(), item.key()) == keys.end())
      Fail("{}: unknown key '{}' (known: {})", where, item.key(), fmt::join(keys, ", "));
}

std::string CalibrationString(const nlohmann::json& j, const std::string& key, const std::string& where,
                              const std::string& fallback) {
  if (!j.contains(key)) return fallback;
  if (!j[key].is_string() || j[key].get<std::string>().empty())
    Fail("{}.{}: must be a non-empty string", where, key);
  return j[key].get<std::string>();
}

nlohmann::json CalibrationSettings(const nlohmann::json& j, const std::string& key, const std::string& where,
                                   const std::vector<std::string>& reserved) {
  if (!j.contains(key)) return nlohmann::json::object();
  ValidateSettings(j[key], reserved, where + "." + key);
  return j[key];
}

CalibrationVariant ParseCalibrationVariant(const nlohmann::json& j, const std::string& where) {
  CalibrationOnlyKeys(j, where, {"name", "datagen", "calibrate"});
  CalibrationVariant v;
  v.name = CalibrationString(j, "name", where, "");
  if (v.name.empty()) Fail("{}: key 'name' missing", where);
  if (v.name.find_first_of("/\\ ") != std::string::npos || v.name == "." || v.name == "..")
    Fail("{}.name: '{}' is a folder name: no slashes or spaces", where, v.name);
  v.datagen = CalibrationSettings(j, "datagen", where, kCalibrationReservedDatagen);
  v.calibrate = CalibrationSettings(j, "calibrate", where, kCalibrationReservedCalibrate);
  return v;
}

// The ladder stops at the first rung that registers everything: the last rung's model.
std::string ColmapModelOf(const fs::path& colmap) {
  std::vector<fs::path> models;
  for (const auto& entry : fs::recursive_directory_iterator(colmap))
    if (entry.path().filename() == "cameras.bin") models.push_back(entry.path().parent_path());
  if (models.empty()) Fail("{}: no COLMAP model (cameras.bin) to reuse", colmap.string());
  std::sort(models.begin(), models.end());
  return models.back().string();
}

std::string VariantFolder(const CalibrationVariant& v, int seed) { return fmt::format("{}_s{}", v.name, seed); }

std::vector<std::string> DatagenArgs(const CalibrationGrid& grid, const CalibrationVariant& v, int seed,
                                     const fs::path& dir) {
  std::vector<std::string> args = {SelfExecutable().string(), "datagen", "--capture", "--scene", grid.scene,
                                   "--preset", grid.preset, "--seed", std::to_string(seed),
                                   "--out", (dir / "capture").string()};
  const auto flags = SettingsToArgs(MergeSettings(grid.datagen, v.datagen), 0, grid.file.string());
  args.insert(args.end(), flags.begin(), flags.end());
  return args;
}

std::vector<std::string> CalibrateArgs(const CalibrationGrid& grid, const CalibrationVariant& v,
                                       const fs::path& dir) {
  const fs::path capture = dir / "capture" / grid.scene;
  std::vector<std::string> args = {SelfExecutable().string(), "calibrate", "--capture", capture.string(),
                                   "--out", (dir / "calibrated").string(), "--truth", (capture / "truth").string()};
  // A COLMAP model of an earlier calibration (moved aside before it is replaced) is reused.
  if (fs::exists(dir / "colmap")) args.insert(args.end(), {"--colmap-model", ColmapModelOf(dir / "colmap")});
  const auto flags = SettingsToArgs(MergeSettings(grid.calibrate, v.calibrate), 0, grid.file.string());
  args.insert(args.end(), flags.begin(), flags.end());
  return args;
}

double CalibrationNumber(const nlohmann::json& j, const char* key, const fs::path& file) {
  if (!j.contains(key) || !j[key].is_number()) Fail("{}: '{}' missing or not a number", file.string(), key);
  return j[key].get<double>();
}

std::string RegistrationOf(const fs::path& calibrated) {
  const fs::path rig_file = calibrated / "rig.json";
  const nlohmann::json rig = ReadJsonFile(rig_file);
  const std::string source = rig.value("model_source", "");
  std::smatch rung;
  const bool laddered = std::regex_search(source, rung, std::regex("rung (\\d+) of the registration ladder"));
  int weakest = -1;
  for (const auto& camera : rig.value("cameras", nlohmann::json::array()))
    if (camera.contains("observations") && camera["observations"].is_number_integer())
      weakest = weakest < 0 ? camera["observations"].get<int>() : std::min(weakest, camera["observations"].get<int>());
  return fmt::format("all cameras, extra {}, {}{}", rig.value("extra_images_registered", 0),
                     laddered ? "rung " + rung[1].str() : std::string("given model"),
                     weakest >= 0 ? fmt::format(", weakest camera {} obs.", weakest) : std::string());
}

std::string DistortionOf(const nlohmann::json& calibration) {
  std::vector<std::string> kept;
  for (const auto& c : calibration.value("cameras", nlohmann::json::array()))
    kept.push_back(!c.value("distortion_kept", false) ? "-" : c.value("distortion_terms", 2) == 1 ? "k1" : "k1k2");
  return fmt::format("{}", fmt::join(kept, " "));
}

// The falloff calibrate divided out of each camera (calibration.json, rig order) against the
// capture's (truth_comparison.json, the same order); absent in older results: nothing counted.
void ReadVignetting(const nlohmann::json& cal, const nlohmann::json& truth, CalibrationRow* r) {
  std::vector<double> applied;
  if (cal.contains("camera_agreement") && cal["camera_agreement"].contains("vignetting_applied"))
    for (const auto& v : cal["camera_agreement"]["vignetting_applied"]) applied.push_back(v.is_number() ? v.get<double>() : 0);
  const auto cameras = truth.value("cameras", nlohmann::json::array());
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    const double v_true = cameras[c].value("vignetting_truth", 0.0), v = c < applied.size() ? applied[c] : 0.0;
    r->vignetting_true += v_true > 0;
    r->vignetting_corrected += v > 0;
    r->vignetting_error = std::max(r->vignetting_error, std::abs(v - v_true));
  }
}

std::vector<std::string> MissedTargets(const CalibrationRow& r, const CalibrationTargets& t) {
  std::vector<std::string> missed;
  if (!(r.rotation_pairs_deg <= t.rotation_deg)) missed.push_back("rotation");
  if (!(r.centre_relative <= t.centre_relative)) missed.push_back("centres");
  if (!(r.focal_relative <= t.focal_relative)) missed.push_back("focal");
  if (!(r.slope >= t.slope_low && r.slope <= t.slope_high)) missed.push_back("slope");
  if (!(r.camera_disagreement <= t.camera_disagreement)) missed.push_back("cameras");
  return missed;
}

}  // namespace

CalibrationGrid ParseCalibrationGrid(const nlohmann::json& doc, const fs::path& file) {
  const std::string where = file.string();
  CalibrationOnlyKeys(doc, where, {"name", "description", "scene", "preset", "datagen", "calibrate", "seeds", "variants"});
  CalibrationGrid grid;
  grid.file = file;
  grid.name = CalibrationString(doc, "name", where, file.stem().string());
  grid.description = CalibrationString(doc, "description", where, "");
  grid.scene = CalibrationString(doc, "scene", where, grid.scene);
  grid.preset = CalibrationString(doc, "preset", where, grid.preset);
  grid.datagen = CalibrationSettings(doc, "datagen", where, kCalibrationReservedDatagen);
  grid.calibrate = CalibrationSettings(doc, "calibrate", where, kCalibrationReservedCalibrate);
  if (doc.contains("seeds")) {
    if (!doc["seeds"].is_array() || doc["seeds"].empty()) Fail("{}.seeds: must be a non-empty array of integers", where);
    grid.seeds.clear();
    for (const auto& s : doc["seeds"]) {
      if (!s.is_number_integer() || s.get<long long>() < 0) Fail("{}.seeds: {} is not a non-negative integer", where, s.dump());
      grid.seeds.push_back(s.get<int>());
    }
  }
  if (!doc.contains("variants") || !doc["variants"].is_array() || doc["variants"].empty())
    Fail("{}: 'variants' must be a non-empty array", where);
  for (std::size_t i = 0; i < doc["variants"].size(); ++i) {
    grid.variants.push_back(ParseCalibrationVariant(doc["variants"][i], fmt::format("{}.variants[{}]", where, i)));
    for (std::size_t k = 0; k + 1 < grid.variants.size(); ++k)
      if (grid.variants[k].name == grid.variants.back().name)
        Fail("{}.variants[{}]: name '{}' is used twice", where, i, grid.variants.back().name);
  }
  return grid;
}

CalibrationGrid LoadCalibrationGrid(const fs::path& file) { return ParseCalibrationGrid(ReadJsonFile(file), file); }

CalibrationRow ReadCalibrationRow(const fs::path& calibrated, const CalibrationTargets& targets) {
  const fs::path truth_file = calibrated / "truth_comparison.json", cal_file = calibrated / "calibration.json";
  const nlohmann::json truth = ReadJsonFile(truth_file), cal = ReadJsonFile(cal_file);
  if (!truth.contains("geometry") || !truth.contains("hdr"))
    Fail("{}: no geometry or HDR comparison (was the capture calibrated with --truth?)", truth_file.string());
  const nlohmann::json& g = truth["geometry"];
  const nlohmann::json& h = truth["hdr"];
  CalibrationRow r;
  r.registration = RegistrationOf(calibrated);
  r.rotation_centres_deg = CalibrationNumber(g, "max_rotation_error_deg", truth_file);
  r.rotation_oriented_deg = CalibrationNumber(g, "max_rotation_error_oriented_deg", truth_file);
  r.rotation_pairs_deg = CalibrationNumber(g, "max_relative_rotation_error_deg", truth_file);
  r.centre_relative = CalibrationNumber(g, "max_position_error_relative", truth_file);
  r.focal_relative = CalibrationNumber(g, "max_focal_error_relative", truth_file);
  r.slope = CalibrationNumber(h, "loglog_slope", truth_file);
  r.slope_render = h.value("loglog_slope_render", -1.0);
  r.slope_render_floor = h.value("loglog_slope_render_floor", -1.0);
  r.hdr_median = CalibrationNumber(h, "median_relative_error", truth_file);
  r.hdr_dark = CalibrationNumber(h, "dark_fifth_median_relative_error", truth_file);
  r.camera_disagreement = CalibrationNumber(h, "camera_disagreement", truth_file);
  r.distortion = DistortionOf(cal);
  if (cal.contains("camera_agreement")) {
    r.sparse_disagreement_after = CalibrationNumber(cal["camera_agreement"], "disagreement_after", cal_file);
    r.held_out_bias = cal["camera_agreement"].value("held_out_bias", 0.0);
  }
  ReadVignetting(cal, truth, &r);
  if (cal.contains("seconds"))
    r.calibrate_seconds = cal["seconds"].value("geometry", 0.0) + cal["seconds"].value("radiometry", 0.0);
  r.missed = MissedTargets(r, targets);
  return r;
}

std::string CalibrationTableMarkdown(const std::vector<CalibrationRow>& rows) {
  std::string md =
      "| variant | seed | registered | rotation max (deg): pairs / orientations / centres' similarity | "
      "centre max (% rig) | focal max | distortion kept | HDR slope (against the render; a perfect calibration there) | HDR median (darkest fifth) | "
      "cameras' HDR scales vs truth | sparse points after gains: scatter / held-out bias | vignetting divided out: cameras (with it), "
      "max error of v | calibrate (s) | targets |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const CalibrationRow& r : rows) {
    if (!r.failed.empty()) {
      md += fmt::format("| {} | {} | failed: {} ||||||||||| missed all |\n", r.variant, r.seed, r.failed);
      continue;
    }
    md += fmt::format(
        "| {} | {} | {} | {:.3f} / {:.3f} / {:.3f} | {:.2f} | {:.2f}% | {} | {:.3f}{} | {:.1f}% ({:.1f}%) | {:.1f}% | "
        "{:.1f}% / {:.1f}% | {} ({}), {:.3f} | {:.0f} | {} |\n",
        r.variant, r.seed, r.registration, r.rotation_pairs_deg, r.rotation_oriented_deg, r.rotation_centres_deg,
        100 * r.centre_relative, 100 * r.focal_relative, r.distortion, r.slope,
        r.slope_render < 0 ? std::string() : fmt::format(" ({:.3f}; {:.3f})", r.slope_render, r.slope_render_floor),
        100 * r.hdr_median, 100 * r.hdr_dark,
        100 * r.camera_disagreement, 100 * r.sparse_disagreement_after, 100 * r.held_out_bias, r.vignetting_corrected,
        r.vignetting_true, r.vignetting_error, r.calibrate_seconds,
        r.missed.empty() ? std::string("all met") : fmt::format("missed: {}", fmt::join(r.missed, ", ")));
  }
  return md;
}

std::string CalibrationTableCsv(const std::vector<CalibrationRow>& rows) {
  std::string csv =
      "variant,seed,failed,rotation_pairs_deg,rotation_oriented_deg,rotation_centres_deg,centre_relative,"
      "focal_relative,distortion,slope,slope_render,slope_render_floor,hdr_median,hdr_dark,camera_disagreement,sparse_after,held_out_bias,"
      "vignetting_corrected,vignetting_true,vignetting_error,calibrate_seconds,missed\n";
  for (const CalibrationRow& r : rows)
    csv += fmt::format("{},{},\"{}\",{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", r.variant, r.seed, r.failed,
                       r.rotation_pairs_deg, r.rotation_oriented_deg, r.rotation_centres_deg, r.centre_relative,
                       r.focal_relative, r.distortion, r.slope, r.slope_render, r.slope_render_floor, r.hdr_median, r.hdr_dark, r.camera_disagreement,
                       r.sparse_disagreement_after, r.held_out_bias, r.vignetting_corrected, r.vignetting_true,
                       r.vignetting_error, r.calibrate_seconds, fmt::join(r.missed, " "));
  return csv;
}

namespace {

// Runs one step of a variant; false (and the row says where) when it failed.
bool RunCalibrationStep(const std::vector<std::string>& argv, const fs::path& log, const char* step,
                        const CalibrationSuiteOptions& options, CalibrationRow* row) {
  ChildOptions child;
  child.argv = argv;
  child.log = log;
  child.timeout_seconds = 60 * options.timeout_minutes;
  const ChildResult result = RunChild(child);
  if (result.ok()) return true;
  row->failed = fmt::format("{}: {} (log: {})", step, result.Describe(), log.string());
  std::replace(row->failed.begin(), row->failed.end(), '"', '\'');
  std::replace(row->failed.begin(), row->failed.end(), '|', '/');
  return false;
}

CalibrationRow RunCalibrationVariant(const CalibrationGrid& grid, const CalibrationVariant& v, int seed,
                                     const CalibrationSuiteOptions& options) {
  const fs::path dir = options.work / VariantFolder(v, seed);
  CalibrationRow row;
  const bool have_capture = fs::exists(dir / "capture" / grid.scene / "truth" / "cameras.json");
  const bool have_result = fs::exists(dir / "calibrated" / "truth_comparison.json");
  if (!have_capture) {
    fs::create_directories(dir);
    if (!RunCalibrationStep(DatagenArgs(grid, v, seed, dir), dir / "datagen.log", "datagen", options, &row))
      return row;
  }
  if (!have_result || options.recalibrate || !have_capture) {
    if (fs::exists(dir / "calibrated" / "colmap")) {
      fs::remove_all(dir / "colmap");
      fs::rename(dir / "calibrated" / "colmap", dir / "colmap");
    }
    fs::remove_all(dir / "calibrated");
    if (!RunCalibrationStep(CalibrateArgs(grid, v, dir), dir / "calibrate.log", "calibrate", options, &row))
      return row;
  }
  try {
    row = ReadCalibrationRow(dir / "calibrated", CalibrationTargets{});
  } catch (const Error& e) {
    row.failed = fmt::format("reading the result: {}", e.what());
  }
  return row;
}

}  // namespace

std::vector<CalibrationRow> RunCalibrationSuite(const CalibrationGrid& grid, const CalibrationSuiteOptions& options) {
  for (const std::string& name : options.only)
    if (std::none_of(grid.variants.begin(), grid.variants.end(), [&](const auto& v) { return v.name == name; }))
      Fail("bench calibration: {} has no variant '{}'", grid.file.string(), name);
  std::vector<CalibrationRow> rows;
  for (const CalibrationVariant& v : grid.variants) {
    if (!options.only.empty() && std::find(options.only.begin(), options.only.end(), v.name) == options.only.end())
      continue;
    for (const int seed : grid.seeds) {
      const fs::path dir = options.work / VariantFolder(v, seed);
      if (options.dry_run) {
        fmt::print("{} seed {}:\n  {}\n  {}\n", v.name, seed, fmt::join(DatagenArgs(grid, v, seed, dir), " "),
                   fmt::join(CalibrateArgs(grid, v, dir), " "));
        continue;
      }
      CalibrationRow row;
      try {
        row = RunCalibrationVariant(grid, v, seed, options);
      } catch (const Error& e) {
        row.failed = e.what();
      }
      row.variant = v.name;
      row.seed = seed;
      rows.push_back(row);
      fmt::print("bench calibration: {} seed {}: {}\n", v.name, seed,
                 !row.failed.empty() ? row.failed
                 : row.missed.empty() ? std::string("every target met")
                                      : fmt::format("missed {}", fmt::join(row.missed, ", ")));
      // Written after every row, so an interrupted grid keeps what it measured.
      WriteTextFileAtomic(options.work / "calibration_table.md", CalibrationTableMarkdown(rows));
      WriteTextFileAtomic(options.work / "calibration_table.csv", CalibrationTableCsv(rows));
    }
  }
  return rows;
}

}  // namespace hdr4d::bench
