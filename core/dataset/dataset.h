// The dataset format (ARCHITECTURE §3): the HDR-4DGS / D-NeRF JSON layout, read so that the
// reference downloads load unchanged, checked so that a broken scene is reported completely
// (every problem, each naming the file, the frame and the key), and never half-loaded.
//
// Scene root:
//   transforms_train.json, transforms_test.json (required), transforms_val.json (optional)
//   point3d.ply (optional initial points; recorded and validated)
// Top level of each JSON: camera_angle_x (radians; required unless fl_x is given), optional
//   fl_x, fl_y, cx, cy, w, h, near, far.
// Per frame: file_path (relative to the root), transform_matrix (4x4 camera-to-world, Blender /
//   OpenGL axes, see core/geometry/camera.h), time (required), exposures (seconds, > 0, default 1; a
//   scalar or a one-element array; log2 stops, seconds = 2**value, under ExposureUnit::kStops,
//   as HDR-HexPlane's dataset/lego writes them: -3, -1, 1 under the same key), exr_file_path (optional HDR ground truth), optional
//   fl_x, fl_y, cx, cy, w, h (per-frame wins over top level), and our extensions camera_id and
//   exposure_index (non-negative integers, ignored by other readers).
// file_path quirk: the reference appends ".png" unless the path ends in .png or jpeg (so a
//   ".jpg" path becomes ".jpg.png", a latent bug there). We append ".png" only when the path
//   does not already end in a known image extension (.png .jpg .jpeg .exr .hdr .tif .tiff
//   .bmp .webp, any case): D-NeRF's extension-less "./train/r_000" gets ".png", "a.jpg" stays.
// Intrinsics: fl_y defaults to fl_x, cx/cy to w/2, h/2 (core/geometry/camera.h pixel convention), w/h
//   to the image's size. fl_x wins over camera_angle_x when both are given.
// Time: normalised to [0,1] by dividing by the largest raw time over every split together when
//   that maximum exceeds 1 (TimeNormalisation::kGlobal). The reference divides each file by its
//   own maximum, which misaligns train and test when their maxima differ; kPerFileReference
//   reproduces it on request.
//
// nerfstudio: a single transforms.json (when there is no transforms_train.json), intrinsics
//   fl_x, fl_y, cx, cy, w, h, `ply_file_path` for the initial points, `time` optional (0), only
//   pinhole cameras (camera_model PINHOLE/SIMPLE_PINHOLE, or OPENCV without distortion). Splits
//   from test_filenames / val_filenames when given, else every 8th frame (index % 8 == 0) is
//   held out for test. Read as layout "nerfstudio"; problems name transforms.json.
// Other layouts: HDR-NeRF synthetic (static; exposure_{train,test}.json maps
//   "<file_path>_<k>.png" to an exposure; each view becomes one frame per exposure, time 0) is
//   read as layout "hdrnerf". HDR-GS's synthetic COLMAP layout (sparse/ and images/ without
//   transforms JSON) is read as layout "hdrgs-colmap" (core/dataset/colmap_layout.h). The LLFF
//   poses_bounds_exps.npy layout is detected and reported as not supported yet.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/camera.h"

namespace hdr4d {

enum class Split { kTrain, kTest, kVal };
const char* SplitName(Split split);  // "train", "test", "val"
// The split called `name`; throws hdr4d::Error naming `what` (the command) for an unknown name.
Split ParseSplit(const std::string& name, const char* what);

enum class TimeNormalisation {
  kGlobal,            // divide by the largest time over train, test and val together (if > 1)
  kPerFileReference,  // the reference's way: each JSON file by its own largest time (if > 1)
};

// How a frame's `exposures` number is read. HDR-HexPlane's JSON gives log2 stops under the same
// key as HDR-4DGS's seconds (no key tells them apart), so the unit is the reader's choice; a
// scene read as seconds whose exposures are all small (|v| <= kStopsLookLimit) with some not
// positive, one of them negative, is reported with the fix (--exposure-unit stops).
enum class ExposureUnit { kSeconds, kStops };
inline constexpr double kStopsLookLimit = 16;  // 2^16: a wider bracket than any camera's
inline constexpr double kMaxStops = 60;        // |stops| read at most: 2^60 s stays finite
const char* ExposureUnitName(ExposureUnit unit);  // "seconds", "stops"
// Throws hdr4d::Error naming `what` (the command) for anything but seconds or stops.
ExposureUnit ParseExposureUnit(const std::string& name, const char* what);
// The help of --exposure-unit, one text for every command that reads a scene (cli/flags.h,
// train's option table).
extern const char* const kExposureUnitHelp;
// The unit a run folder's config.json records its scene's exposures in (key "exposure_unit",
// written by train; a run from before the key: seconds), so that render, view, export and
// --resume read the scene as training did. Throws hdr4d::Error naming `config_path` and the
// key for a value that is not "seconds" or "stops".
ExposureUnit RecordedExposureUnit(const nlohmann::json& config, const std::string& config_path);

struct Frame {
  Split split = Split::kTrain;
  int index = 0;                     // index in its JSON file's frames array
  std::string file_path;             // as written in the JSON
  std::filesystem::path image_path;  // resolved: root / file_path (+ ".png", see above)
  std::optional<std::string> exr_file_path;
  std::optional<std::filesystem::path> hdr_path;  // root / exr_file_path
  double time_raw = 0, time = 0;                  // time = normalised to [0,1]
  double exposure = 1;                            // seconds
  bool exposure_given = false;                    // the JSON had `exposures`
  std::optional<double> exposure_written;  // its number as written (seconds or stops), if any
  int camera_id = -1, exposure_index = -1;        // -1 = not given
  Camera camera;
};

struct Dataset {
  std::filesystem::path root;
  std::string
      layout;  // "hdr4d" (reference layout), "dnerf" (no exposures), "hdrnerf", "nerfstudio"
  std::vector<Frame> train, test, val;
  double camera_angle_x = 0;  // train file's value (or implied by its fl_x when absent)
  std::optional<double> near, far;
  std::optional<std::filesystem::path> point_cloud_path;  // root/point3d.ply if present
  double time_max_raw = 0;                                // largest raw time over every split
  ExposureUnit exposure_unit = ExposureUnit::kSeconds;    // how `exposures` was read
  // Read as seconds, the exposures were all small with some not positive: log2 stops, most
  // likely (a problem says so); `exposure` then holds nothing meaningful.
  bool exposures_look_like_stops = false;

  std::vector<const Frame*> AllFrames() const;  // train, test, val order
  const std::vector<Frame>& FramesOf(Split split) const;
  std::size_t NumFrames() const { return train.size() + test.size() + val.size(); }
};

struct DatasetProblem {
  std::filesystem::path file;  // the JSON (or PLY) file the problem is in
  int frame = -1;              // index in that file's frames array, -1 for the file itself
  std::string key;             // JSON key ("time", "file_path", ...), empty when none applies
  std::string message;
  std::string ToString() const;  // "file: frame N: key: message"
};

enum class ImageCheck {
  // Reads no image, except one header when the JSON declares no w/h (the LDR image, or the
  // HDR one when the LDR is not there yet), which then sizes every frame.
  kNone,
  kHeaders,  // every image's header: existence, readability, sizes
  kFull,     // decodes every image: also finds corrupt pixel data and NaN/Inf in EXR
};

struct DatasetLoadOptions {
  ImageCheck image_check = ImageCheck::kHeaders;
  TimeNormalisation time_normalisation = TimeNormalisation::kGlobal;
  ExposureUnit exposure_unit = ExposureUnit::kSeconds;
  bool require_test = true;
  bool show_progress = false;  // a progress bar on stderr while checking (200+ frames) images
  // A read scene's files and image folders are refused as outputs for the rest of the command
  // (core/files/output_guard.h). Off only for harnesses that build corrupt scenes on purpose
  // (benchmark/stress_kit.cpp).
  bool protect_inputs = true;
};

struct DatasetReport {
  std::vector<DatasetProblem> problems;
  std::optional<Dataset> dataset;  // set when the JSON files parsed far enough to list frames
  std::optional<std::int64_t> point_cloud_points;  // vertex count of point3d.ply when readable
  bool ok() const { return problems.empty(); }
};

// Checks a scene and collects EVERY problem (sorted by file, then frame). Never throws for a
// bad scene; the problems say what is wrong.
DatasetReport CheckDataset(const std::filesystem::path& root,
                           const DatasetLoadOptions& options = {});

// Loads a scene; throws hdr4d::Error listing the problems (the first 10 and how many more)
// when there is any, so it never returns a half-loaded dataset.
Dataset LoadDataset(const std::filesystem::path& root, const DatasetLoadOptions& options = {});

// The resolved image path for a JSON file_path (appends ".png" as documented above).
std::filesystem::path ResolveImagePath(const std::filesystem::path& root,
                                       const std::string& file_path);

struct DatasetWriteOptions {
  bool write_val = true;  // write transforms_val.json when the dataset has val frames
};

// Writes transforms_{train,test[,val]}.json into `root` from the frames: file_path,
// transform_matrix, time (= time_raw), exposures (when exposure_given), exr_file_path,
// camera_id and exposure_index (when >= 0). Top level: camera_angle_x (the dataset's, or
// implied by the first frame), w and h when every frame shares a size, near/far when set,
// and fl_x/fl_y/cx/cy when every frame shares intrinsics that differ from those implied by
// camera_angle_x; a frame whose intrinsics differ from the top level gets its own keys.
// A frame with an empty file_path uses image_path (relative to `root` when absolute); the same
// for exr_file_path / hdr_path. Each file is written atomically. Images are not copied.
// Throws hdr4d::Error naming the file and frame for an invalid pose, time or exposure.
void WriteDataset(const Dataset& dataset,
                  const std::filesystem::path& root,
                  const DatasetWriteOptions& options = {});

// Moves a dataset's paths (root, images, HDR images, point cloud) from under its root to under
// `new_root`, after its folder was moved there (a scene built in a staging folder).
void RebaseDataset(Dataset* dataset, const std::filesystem::path& new_root);

}  // namespace hdr4d
