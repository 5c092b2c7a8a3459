#include "calibration/calibrate.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <numeric>

#include "calibration/board_calibration.h"
#include "calibration/calibration_report.h"
#include "calibration/camera_gains.h"
#include "calibration/capture.h"
#include "calibration/colmap_driver.h"
#include "calibration/rig_geometry.h"
#include "calibration/undistort.h"
#include "core/geometry/colmap_model.h"
#include "core/dataset/dataset.h"
#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/util/progress.h"

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

Bracket LoadBracket(const fs::path& path, double exposure, const std::string& camera, int frame) {
  if (IsHdrPath(path))
    Fail("{}: camera {}, frame {}: EXR brackets are not supported yet (use JPEG, PNG or TIFF)",
         path.string(), camera, frame);
  Bracket b;
  b.image = ReadImage(path);
  if (b.image.channels() < 3)
    Fail("{}: camera {}, frame {}: {} channel(s); calibrate needs colour images", path.string(),
         camera, frame, b.image.channels());
  if (b.image.channels() > 3) b.image = b.image.Rgb();
  b.exposure = exposure;
  b.name = path.string();
  return b;
}

std::vector<Bracket> LoadFrame(const CaptureCamera& camera, const CaptureFrame& frame) {
  std::vector<Bracket> brackets;
  for (std::size_t k = 0; k < frame.brackets.size(); ++k)
    brackets.push_back(LoadBracket(frame.brackets[k], frame.exposures[k], camera.name, frame.index));
  return brackets;
}

std::optional<Rig> RunGeometry(const Capture& capture, const CalibrateOptions& options,
                               const fs::path& staging) {
  fs::path model_folder;
  std::string source;
  if (options.colmap_model) {
    model_folder = FindColmapModelFolder(*options.colmap_model);
    source = fmt::format("given ({})", model_folder.string());
  } else {
    for (const CaptureCamera& camera : capture.cameras)
      if (camera.static_images.empty())
        Fail("{}: camera {} has no static images; COLMAP needs at least one per camera",
             (capture.root / "static" / camera.name).string(), camera.name);
    ColmapRunOptions colmap;
    colmap.binary = options.colmap_binary;
    colmap.show_progress = options.show_progress;
    colmap.max_image_size = options.colmap_max_image_size;
    model_folder = RunColmap(capture.root / "static", staging / "colmap", colmap);
    source = "COLMAP 3.8 (SIFT on CPU, exhaustive matching, incremental mapping)";
  }
  const ColmapModel model = ReadColmapModel(model_folder);
  std::vector<std::string> names;
  for (const CaptureCamera& camera : capture.cameras) names.push_back(camera.name);
  RigOptions rig_options;
  rig_options.undistort_threshold_pixels = options.undistort_threshold_pixels;
  rig_options.show_progress = options.show_progress;
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

// Writes images/, hdr/, response.* into `staging` and returns the dataset frames (one per
// bracket) when the rig is known.
std::vector<Frame> RunRadiometry(const Capture& capture, const CalibrateOptions& options,
                                 const std::optional<Rig>& rig, const fs::path& staging,
                                 CalibrationRecord* record, int* images_written) {
  std::vector<std::vector<Bracket>> stacks;
  for (const CaptureCamera& camera : capture.cameras)
    stacks.push_back(LoadFrame(camera, camera.frames.front()));
  const CameraResponse response = RecoverResponse(stacks, options.response);
  WriteResponseCsv((staging / "response.csv").string(), response);
  WriteResponsePlot((staging / "response.png").string(), response);
  record->response_method = response.method;

  // Unlike cameras: gains from the first frame of every camera on the points they share.
  std::optional<CameraGains> gains;
  if (rig && !rig->visibility.empty() && capture.cameras.size() >= 2) {
    std::vector<Image> first;
    for (std::size_t c = 0; c < capture.cameras.size(); ++c)
      first.push_back(FuseBrackets(c < stacks.size() ? stacks[c] : LoadFrame(capture.cameras[c], capture.cameras[c].frames.front()),
                                   response, options.fusion).hdr);
    std::vector<Image> ordered;  // the rig's camera order
    for (const RigCamera& rc : rig->cameras)
      for (std::size_t c = 0; c < capture.cameras.size(); ++c)
        if (capture.cameras[c].name == rc.name) ordered.push_back(first[c]);
    if (ordered.size() == rig->cameras.size()) gains = EstimateCameraGains(*rig, ordered);
  }
  record->gains = gains;
  record->gains_applied = gains.has_value() && options.correct_gains;
  auto gain_of = [&](const std::string& name) -> std::array<double, 3> {
    if (!gains || !options.correct_gains) return {1.0, 1.0, 1.0};
    for (std::size_t c = 0; c < rig->cameras.size(); ++c)
      if (rig->cameras[c].name == name) return gains->gain[c];
    return {1.0, 1.0, 1.0};
  };

  std::size_t total = 0;
  for (const CaptureCamera& camera : capture.cameras) total += camera.frames.size();
  Progress progress("fuse", static_cast<std::int64_t>(total), options.show_progress);
  std::vector<Frame> frames;
  for (std::size_t c = 0; c < capture.cameras.size(); ++c) {
    const CaptureCamera& camera = capture.cameras[c];
    const RigCamera* rig_camera = rig ? rig->Find(camera.name) : nullptr;
    if (rig && !rig_camera)
      Fail("{}: camera {} is not in the rig of rig.json", (capture.root / "sequence" / camera.name).string(),
           camera.name);
    for (const CaptureFrame& capture_frame : camera.frames) {
      std::vector<Bracket> brackets = LoadFrame(camera, capture_frame);
      if (rig_camera && (brackets.front().image.width() != rig_camera->width ||
                         brackets.front().image.height() != rig_camera->height))
        Fail("{}: camera {}, frame {}: size {}x{} differs from the static images' {}x{}",
             brackets.front().name, camera.name, capture_frame.index, brackets.front().image.width(),
             brackets.front().image.height(), rig_camera->width, rig_camera->height);
      FusionResult fused = FuseBrackets(brackets, response, options.fusion);
      const std::array<double, 3> gain = gain_of(camera.name);
      for (std::size_t i = 0; i < fused.hdr.size(); ++i) fused.hdr.data()[i] /= static_cast<float>(gain[i % 3]);
      const bool undistort = rig_camera && rig_camera->undistort;
      if (undistort) fused.hdr = Undistort(fused.hdr, rig_camera->intrinsics);
      const std::string hdr_name = fmt::format("hdr/{}/{:05d}.exr", camera.name, capture_frame.index);
      WriteImage(staging / hdr_name, fused.hdr);
      ++*images_written;
      record->frames.push_back({camera.name, capture_frame.index, fused.dynamic_range_stops,
                                fused.motion_fraction, fused.reference_bracket});
      for (std::size_t k = 0; k < brackets.size(); ++k) {
        const fs::path& source = capture_frame.brackets[k];
        std::string ext = source.extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
        const bool copy = !undistort && (ext == ".png" || ext == ".jpg" || ext == ".jpeg");
        const std::string name = fmt::format("images/{}/{}{}", camera.name, source.stem().string(),
                                             copy ? ext : ".png");
        fs::create_directories((staging / name).parent_path());
        if (copy) {
          fs::copy_file(source, staging / name, fs::copy_options::overwrite_existing);
        } else {
          const Image ldr = undistort ? Undistort(brackets[k].image, rig_camera->intrinsics) : brackets[k].image;
          WriteImage(staging / name, ldr, {.format = PixelFormat::kUint16});
        }
        ++*images_written;
        if (!rig_camera) continue;
        Frame frame;
        frame.file_path = name;
        frame.exr_file_path = hdr_name;
        frame.time_raw = capture_frame.time ? *capture_frame.time : capture_frame.index / options.fps;
        // The camera's overall gain becomes part of its effective exposure, so that
        // LDR = response(radiance x exposure) holds for the corrected radiance.
        frame.exposure = capture_frame.exposures[k] * (gain[0] + gain[1] + gain[2]) / 3;
        frame.exposure_given = true;
        frame.camera_id = static_cast<int>(c);
        frame.exposure_index = static_cast<int>(k);
        frame.camera.intrinsics = {rig_camera->intrinsics.f, rig_camera->intrinsics.f,
                                   rig_camera->intrinsics.cx, rig_camera->intrinsics.cy,
                                   rig_camera->width, rig_camera->height};
        frame.camera.world_from_cam_gl = rig_camera->world_from_cam_gl;
        frames.push_back(std::move(frame));
      }
      progress.Advance(1, fmt::format("{} frame {}", camera.name, capture_frame.index));
    }
  }
  progress.Finish();
  return frames;
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
  CheckWritable(out);
  const fs::path staging = out.parent_path() / ("." + out.filename().string() + ".calibrate-partial");
  std::error_code ec;
  fs::remove_all(staging, ec);
  fs::create_directories(staging, ec);
  if (ec) Fail("{}: cannot create the staging folder ({})", staging.string(), ec.message());

  CalibrationRecord record;
  record.warnings = capture.warnings;
  CalibrateSummary summary;
  summary.cameras = static_cast<int>(capture.cameras.size());
  summary.frames = capture.cameras.front().frames.empty() ? 0 : static_cast<int>(capture.cameras.front().frames.size());
  try {
    const bool geometry = options.stage != CalibrationStage::kRadiometry;
    const bool radiometry = options.stage != CalibrationStage::kGeometry;
    if (geometry) {
      fmt::print(stderr, "calibrate: geometry of {} cameras\n", capture.cameras.size());
      const auto start = std::chrono::steady_clock::now();
      record.rig = RunGeometry(capture, options, staging);
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
  } catch (...) {
    fs::remove_all(staging, ec);
    throw;
  }
  return summary;
}

}  // namespace hdr4d
