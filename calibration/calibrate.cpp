#include "calibration/calibrate.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <numeric>

#include "calibration/board_calibration.h"
#include "calibration/calibration_report.h"
#include "calibration/capture.h"
#include "calibration/colmap_driver.h"
#include "calibration/radiometry_stage.h"
#include "calibration/registration_ladder.h"
#include "calibration/rig_geometry.h"
#include "calibration/rig_time_points.h"
#include "core/geometry/colmap_model.h"
#include "core/dataset/dataset.h"
#include "core/files/made_folders.h"
#include "core/util/error.h"
#include "core/image/image_io.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Fails now, before any work, when `out` cannot take files.
void CheckWritable(const fs::path& out) {
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    Fail("{}: --out exists and is not a folder", out.string());
  fs::create_directories(out, ec);
  if (ec) Fail("{}: cannot create the output folder ({})", out.string(), ec.message());
  const fs::path probe = out / ".calibrate-write-test";
  {
    std::FILE* f = std::fopen(probe.c_str(), "wb");
    if (!f) Fail("{}: the output folder is not writable", out.string());
    std::fclose(f);
  }
  fs::remove(probe, ec);
}

// Whether `inner` is `outer` or lies under it, both resolved (symlinks included).
bool IsWithin(const fs::path& inner, const fs::path& outer) {
  const fs::path a = fs::weakly_canonical(inner), b = fs::weakly_canonical(outer);
  auto it = a.begin();
  for (const fs::path& part : b) {
    if (part.empty()) continue;  // the "" of a trailing '/'
    if (it == a.end() || *it != part) return false;
    ++it;
  }
  return true;
}

// The results replace same-named entries of --out (static/, sequence/ are a capture's own):
// --out may be neither the capture, nor inside it, nor hold it.
void CheckOutApartFromCapture(const fs::path& out, const fs::path& capture) {
  if (IsWithin(out, capture))
    Fail("--out {}: inside the capture {} (or the capture itself); calibrate writes beside a "
         "capture, never into it", out.string(), capture.string());
  if (IsWithin(capture, out))
    Fail("--out {}: holds the capture {}; its results would replace the capture's files",
         out.string(), capture.string());
}

// Moves what the run staged into `out`, replacing entries of the same name.
void Publish(const fs::path& staging, const fs::path& out) {
  for (const auto& entry : fs::directory_iterator(staging)) {
    const fs::path target = out / entry.path().filename();
    std::error_code ec;
    fs::remove_all(target, ec);
    fs::rename(entry.path(), target, ec);
    if (ec) Fail("{}: cannot move the result into place ({})", target.string(), ec.message());
  }
  fs::remove_all(staging);
}

// The shorter side a static image needs for COLMAP. Its covariant SIFT (the ladder's third rung)
// aborts inside VLFeat below 16 px ("exit 134", COLMAP 3.8, measured); at 24 px SIFT found ~19
// features on a textured image, hardly more than the 15 inliers COLMAP needs to match two
// views. 32 px keeps a margin; the 120- and 240-px test captures calibrate.
constexpr int kMinColmapSide = 32;

void CheckColmapImageSizes(const Capture& capture) {
  for (const CaptureCamera& camera : capture.cameras) {
    for (const fs::path& path : camera.static_images) {
      const Image image = ReadImage(path);
      if (std::min(image.width(), image.height()) < kMinColmapSide)
        Fail("{}: camera {}: {}x{} pixels; COLMAP's features need at least {} on the shorter "
             "side", path.string(), camera.name, image.width(), image.height(), kMinColmapSide);
    }
  }
}

// COLMAP through the registration ladder: the model folder, what the report says of it in
// `source`, and the warnings of a weak or unchecked model in `notes`.
fs::path RegisterWithColmap(const Capture& capture, const CalibrateOptions& options, const fs::path& staging,
                            std::string* source, std::vector<std::string>* notes) {
  for (const CaptureCamera& camera : capture.cameras)
    if (camera.static_images.empty())
      Fail("{}: camera {} has no static images; COLMAP needs at least one per camera",
           (capture.root / "static" / camera.name).string(), camera.name);
  CheckColmapImageSizes(capture);
  ColmapRunOptions colmap;
  colmap.binary = options.colmap_binary;
  colmap.show_progress = options.show_progress;
  colmap.max_image_size = options.colmap_max_image_size;
  const LadderResult ladder = RegisterWithLadder(capture, staging / "colmap", colmap);
  *source = fmt::format("COLMAP 3.8 (SIFT on CPU, exhaustive matching, incremental mapping), rung {} of the "
                        "registration ladder ({}; tried: {})", ladder.rung, ladder.rung_name,
                        fmt::join(ladder.attempts, "; "));
  if (!ladder.cross_check.empty()) *source += "; " + ladder.cross_check;
  if (ladder.cross_check_weak && ladder.weakest_observations >= kWeakCameraObservations)
    notes->push_back(fmt::format("COLMAP's model could not be confirmed by an independent rung of the registration "
                                 "ladder ({}): check the poses", ladder.cross_check));
  if (ladder.weakest_observations < kWeakCameraObservations)
    notes->push_back(fmt::format("a rig camera has only {} triangulated observations (under {}): too few to pin its "
                                 "focal length and distortion by self-calibration, and so few that the whole model can be "
                                 "wrong (a 320x240 rig with 3 hand-held views came out mirrored); {}; hand-held views of "
                                 "the scene (static/extra/) give COLMAP more",
                                 ladder.weakest_observations, kWeakCameraObservations,
                                 ladder.cross_check.empty() ? "not cross-checked" : ladder.cross_check));
  if (!ladder.unregistered.empty())
    notes->push_back(fmt::format("COLMAP left {} unregistered after every rung of the registration ladder",
                                 fmt::join(ladder.unregistered, ", ")));
  return ladder.model_folder;
}

std::optional<Rig> RunGeometry(const Capture& capture, const CalibrateOptions& options,
                               const fs::path& staging, std::vector<std::string>* notes) {
  fs::path model_folder;
  std::string source;
  if (options.colmap_model) {
    model_folder = FindColmapModelFolder(*options.colmap_model);
    source = fmt::format("given ({})", model_folder.string());
  } else {
    model_folder = RegisterWithColmap(capture, options, staging, &source, notes);
  }
  const ColmapModel model = ReadColmapModel(model_folder);
  std::vector<std::string> names;
  for (const CaptureCamera& camera : capture.cameras) names.push_back(camera.name);
  RigOptions rig_options;
  rig_options.undistort_threshold_pixels = options.undistort_threshold_pixels;
  rig_options.shared_intrinsics = options.shared_intrinsics;
  rig_options.select_distortion = options.select_distortion;
  rig_options.refine = options.refine_rig;
  rig_options.select_shared_focal = options.select_shared_focal;
  rig_options.show_progress = options.show_progress;
  if (options.focal_multistart) rig_options.focal_starts = DefaultFocalStarts();
  if (options.rig_time_points) {
    rig_options.rig_times = ExtractRigTimes(capture, names, options.show_progress);
    if (rig_options.rig_times.empty())
      notes->push_back("--rig-time-points: the capture has no sequence frames to match; COLMAP's points only");
  }
  std::vector<BoardCalibration> boards;
  std::vector<std::string> board_notes;
  if (!options.board.empty()) {
    const BoardSpec spec = ParseBoardSpec(options.board);
    for (const CaptureCamera& camera : capture.cameras) {
      boards.push_back(CalibrateFromBoard(camera.static_images, spec));
      const BoardCalibration& b = boards.back();
      if (b.views > 0) {
        rig_options.board_intrinsics[camera.name] = b.intrinsics;
        board_notes.push_back(fmt::format("{} ({} views, {:.2f} px)", camera.name, b.views, b.rms));
      }
    }
  }
  Rig rig = RigFromColmap(model, names, rig_options);
  rig.model_source = source;
  notes->insert(notes->end(), rig.notes.begin(), rig.notes.end());
  if (!board_notes.empty()) {
    rig.intrinsics_source = fmt::format("checkerboard {} for {}; COLMAP, refined with Ceres, for the others",
                                        options.board, fmt::join(board_notes, ", "));
    // Metric scale: every pair of cameras that saw the board at the same moment.
    std::vector<double> scales;
    for (std::size_t a = 0; a < boards.size(); ++a)
      for (std::size_t b = a + 1; b < boards.size(); ++b) {
        const double units = (rig.cameras[a].world_from_cam_gl.topRightCorner<3, 1>() -
                              rig.cameras[b].world_from_cam_gl.topRightCorner<3, 1>()).norm();
        if (const double m = MetresPerUnit(boards[a], boards[b], units); m > 0) scales.push_back(m);
      }
    if (!scales.empty()) rig.metres_per_unit = std::accumulate(scales.begin(), scales.end(), 0.0) / scales.size();
  }
  WriteRigJson(staging / "rig.json", rig);
  WritePly(staging / "point3d.ply", rig.points);
  return rig;
}

void WriteCalibratedDataset(std::vector<Frame> frames, const Capture& capture,
                            const CalibrateOptions& options, const fs::path& staging,
                            CalibrationRecord* record) {
  std::string test = options.test_camera;
  if (test.empty() && capture.cameras.size() >= 2) test = capture.cameras.back().name;
  int test_id = -1;
  for (std::size_t c = 0; c < capture.cameras.size(); ++c)
    if (capture.cameras[c].name == test) test_id = static_cast<int>(c);
  if (!test.empty() && test_id < 0) Fail("--test-camera {}: no such camera in the capture", test);
  Dataset dataset;
  dataset.root = staging;
  dataset.layout = "hdr4d";
  double last_time = 0;
  for (const Frame& frame : frames) last_time = std::max(last_time, frame.time_raw);
  for (Frame& frame : frames) {
    // One camera: its last frame is the test split (novel time rather than novel view).
    const bool is_test = test_id >= 0 ? frame.camera_id == test_id : frame.time_raw == last_time;
    frame.split = is_test ? Split::kTest : Split::kTrain;
    (is_test ? dataset.test : dataset.train).push_back(frame);
  }
  if (dataset.train.empty()) dataset.train = dataset.test;  // a single frame of a single camera
  dataset.camera_angle_x = dataset.train.front().camera.intrinsics.FovX();
  WriteDataset(dataset, staging);
  record->test_camera = test.empty() ? fmt::format("{} (last frame)", capture.cameras.front().name) : test;
}

// The stages in order, everything written into `staging`, published into `out` at the end.
CalibrateSummary RunStages(const Capture& capture, const CalibrateOptions& options, const fs::path& out,
                           const fs::path& staging) {
  CalibrationRecord record;
  record.warnings = capture.warnings;
  CalibrateSummary summary;
  summary.cameras = static_cast<int>(capture.cameras.size());
  summary.frames = capture.cameras.front().frames.empty() ? 0 : static_cast<int>(capture.cameras.front().frames.size());
  std::error_code ec;
  const bool geometry = options.stage != CalibrationStage::kRadiometry;
  const bool radiometry = options.stage != CalibrationStage::kGeometry;
  if (geometry) {
    fmt::print(stderr, "calibrate: geometry of {} cameras\n", capture.cameras.size());
    const auto start = std::chrono::steady_clock::now();
    record.rig = RunGeometry(capture, options, staging, &record.warnings);
    record.geometry_run = true;
    summary.seconds_geometry = record.seconds_geometry = SecondsSince(start);
  } else if (fs::exists(out / "rig.json", ec)) {
    record.rig = ReadRigJson(out / "rig.json");
  }
  if (radiometry) {
    fmt::print(stderr, "calibrate: radiometry of {} frames x {} cameras x {} brackets\n",
               summary.frames, summary.cameras, capture.brackets_per_frame);
    const auto start = std::chrono::steady_clock::now();
    std::vector<Frame> frames =
        RunRadiometry(capture, options, record.rig, staging, &record, &summary.images_written);
    summary.seconds_radiometry = record.seconds_radiometry = SecondsSince(start);
    if (record.rig) {
      WriteCalibratedDataset(std::move(frames), capture, options, staging, &record);
      summary.dataset_written = true;
    } else {
      record.warnings.push_back("no rig.json: the transforms were not written; run --stage geometry");
    }
  }
  WriteCalibrationReport(staging, record);
  Publish(staging, out);
  // The capture's own warnings were printed when it was scanned; the stages' are printed here,
  // so that a weak model is not said in report.md alone.
  for (std::size_t k = capture.warnings.size(); k < record.warnings.size(); ++k)
    spdlog::warn("calibrate: {}", record.warnings[k]);
  return summary;
}

}  // namespace

CalibrationStage ParseCalibrationStage(const std::string& name) {
  if (name == "geometry") return CalibrationStage::kGeometry;
  if (name == "radiometry") return CalibrationStage::kRadiometry;
  if (name == "all") return CalibrationStage::kAll;
  Fail("--stage {}: use geometry, radiometry or all", name);
}

CalibrateSummary Calibrate(const CalibrateOptions& options) {
  if (!(options.fps > 0) || !std::isfinite(options.fps)) Fail("--fps must be positive");
  const Capture capture = ScanCapture(options.capture, options.stage != CalibrationStage::kGeometry);
  for (const std::string& w : capture.warnings) spdlog::warn("calibrate: {}", w);
  fs::path out = fs::absolute(options.out).lexically_normal();
  if (out.filename().empty()) out = out.parent_path();
  CheckOutApartFromCapture(out, options.capture);
  const fs::path created = FirstMissingFolder(out);
  const fs::path staging = out.parent_path() / ("." + out.filename().string() + ".calibrate-partial");
  try {
    CheckWritable(out);
    std::error_code ec;
    fs::remove_all(staging, ec);
    fs::create_directories(staging, ec);
    if (ec) Fail("{}: cannot create the staging folder ({})", staging.string(), ec.message());
    return RunStages(capture, options, out, staging);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(staging, ec);
    RemoveIfEmptyTree(created);
    throw;
  }
}

}  // namespace hdr4d
