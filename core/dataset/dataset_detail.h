// The parts of the dataset reader shared by its files (not for use outside core/dataset/dataset*.cpp):
// problems ranked by file, typed JSON access that records every problem against (file, frame,
// key), and the frames as parsed before their images are checked. ARCHITECTURE §3.
#pragma once

#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "core/dataset/dataset.h"

namespace hdr4d::dataset_detail {

namespace fs = std::filesystem;
using nlohmann::json;

// Where each kind of file sorts in a report: the root itself first, then per split the
// transforms file and its HDR-NeRF exposure file, then the point cloud.
enum FileRank { kRankRoot = 0, kRankPointCloud = 100 };
inline int SplitRank(Split split, bool exposure_file) {
  return 10 + 10 * static_cast<int>(split) + exposure_file;
}

struct RankedProblem {
  int rank = 0;
  DatasetProblem problem;
};

class ProblemSink {
 public:
  void Add(int rank, const fs::path& file, int frame, std::string key, std::string message) {
    problems_.push_back({rank, {file, frame, std::move(key), std::move(message)}});
  }
  std::vector<DatasetProblem> Sorted() {
    std::stable_sort(problems_.begin(), problems_.end(),
                     [](const RankedProblem& a, const RankedProblem& b) {
                       return std::tie(a.rank, a.problem.frame) < std::tie(b.rank, b.problem.frame);
                     });
    std::vector<DatasetProblem> out;
    out.reserve(problems_.size());
    for (RankedProblem& p : problems_) out.push_back(std::move(p.problem));
    return out;
  }

 private:
  std::vector<RankedProblem> problems_;
};

// Error messages from the I/O helpers start with the file's path; the problem names the file
// already, so drop the repetition.
inline std::string WithoutPathPrefix(const std::string& message, const fs::path& path) {
  const std::string prefix = path.string() + ": ";
  return message.rfind(prefix, 0) == 0 ? message.substr(prefix.size()) : message;
}

// A short preview of a bad value for a problem line (never the whole value: it may be huge).
std::string Describe(const json& value);

// Typed access to one JSON object with every problem recorded against (file, frame, key).
class Reader {
 public:
  Reader(ProblemSink& sink, int rank, fs::path file)
      : sink_(sink), rank_(rank), file_(std::move(file)) {}

  void Problem(int frame, std::string key, std::string message) const {
    sink_.Add(rank_, file_, frame, std::move(key), std::move(message));
  }
  const fs::path& file() const { return file_; }

  // nullopt when absent (no problem) or ill-typed (a problem).
  std::optional<double> Number(const json& obj, int frame, const char* key) const {
    const auto it = obj.find(key);
    if (it == obj.end()) return std::nullopt;
    if (!it->is_number()) {
      Problem(frame, key, "expected a number, got " + Describe(*it));
      return std::nullopt;
    }
    const double value = it->get<double>();
    if (!std::isfinite(value)) {
      Problem(frame, key, fmt::format("value {} is not finite", value));
      return std::nullopt;
    }
    return value;
  }

  std::optional<double> PositiveNumber(const json& obj, int frame, const char* key) const {
    const std::optional<double> value = Number(obj, frame, key);
    if (value && !(*value > 0)) {
      Problem(frame, key, fmt::format("must be positive, got {}", *value));
      return std::nullopt;
    }
    return value;
  }

  std::optional<int> Int(const json& obj, int frame, const char* key, int min_value) const {
    const auto it = obj.find(key);
    if (it == obj.end()) return std::nullopt;
    double value = 0;
    if (it->is_number()) value = it->get<double>();
    if (!it->is_number() || value != std::floor(value) || std::abs(value) > 1e9) {
      Problem(frame, key, "expected an integer, got " + Describe(*it));
      return std::nullopt;
    }
    if (value < min_value) {
      Problem(frame, key, fmt::format("must be at least {}, got {}", min_value, value));
      return std::nullopt;
    }
    return static_cast<int>(value);
  }

  std::optional<std::string> String(const json& obj, int frame, const char* key) const {
    const auto it = obj.find(key);
    if (it == obj.end()) return std::nullopt;
    if (!it->is_string()) {
      Problem(frame, key, "expected a string, got " + Describe(*it));
      return std::nullopt;
    }
    std::string value = it->get<std::string>();
    if (value.empty()) {
      Problem(frame, key, "is empty");
      return std::nullopt;
    }
    return value;
  }

 private:
  ProblemSink& sink_;
  int rank_;
  fs::path file_;
};

// Intrinsics keys as written, top level or per frame.
struct IntrinsicsKeys {
  std::optional<double> fl_x, fl_y, cx, cy;
  std::optional<int> w, h;

  void Read(const Reader& r, const json& obj, int frame) {
    fl_x = r.PositiveNumber(obj, frame, "fl_x");
    fl_y = r.PositiveNumber(obj, frame, "fl_y");
    cx = r.Number(obj, frame, "cx");
    cy = r.Number(obj, frame, "cy");
    w = r.Int(obj, frame, "w", 1);
    h = r.Int(obj, frame, "h", 1);
  }
  // Per-frame keys win over the file's.
  IntrinsicsKeys Over(const IntrinsicsKeys& top) const {
    IntrinsicsKeys k;
    k.fl_x = fl_x ? fl_x : top.fl_x;
    k.fl_y = fl_y ? fl_y : top.fl_y;
    k.cx = cx ? cx : top.cx;
    k.cy = cy ? cy : top.cy;
    k.w = w ? w : top.w;
    k.h = h ? h : top.h;
    return k;
  }
};

// A frame plus what is needed to finish it once image sizes are known.
struct PendingFrame {
  Frame frame;
  int rank = 0;  // of its transforms file
  fs::path json_path;
  IntrinsicsKeys keys;   // per frame over top level
  bool image_ok = true;  // false once an image problem was reported
  bool exposure_key = false;  // the frame's JSON has `exposures` (valid or not)
  bool time_key = false;      // ... and `time`
};

struct SplitFile {
  Split split = Split::kTrain;
  fs::path path;
  bool parsed = false;
  std::optional<double> camera_angle_x;
  std::optional<double> near, far;
  std::vector<PendingFrame> frames;
};

// HDR-NeRF: exposure_<split>.json maps "<file_path>_<k>.png" to the exposure time.
struct ExposureTable {
  Reader reader;  // problems name the exposure file, the view's frame index and the image name
  json values;
};

// What the transforms files of a native scene held.
struct SceneFiles {
  bool nerfstudio = false;                 // one transforms.json for every split
  bool hdrnerf = false;                    // exposure_<split>.json beside the transforms files
  std::optional<fs::path> nerfstudio_ply;  // its `ply_file_path`
  std::array<SplitFile, 3> files;          // train, test, val
  std::vector<fs::path> json_files;        // every JSON file of the scene that was read
};

// ---- dataset_reading.cpp: the JSON files, key by key ----------------------------------------

// Parses one transforms file into pending frames (images are checked later).
void ParseSplitFile(const fs::path& root,
                    SplitFile& file,
                    const json& doc,
                    const Reader& r,
                    const ExposureTable* hdrnerf,
                    bool time_optional = false,
                    ExposureUnit unit = ExposureUnit::kSeconds);
// Reads every transforms file (and HDR-NeRF exposure file) of a native scene.
SceneFiles ReadSceneFiles(const fs::path& root,
                          const DatasetLoadOptions& options,
                          ProblemSink& sink);
// Read as seconds, exposures that are all small (|v| <= kStopsLookLimit) with some not positive,
// at least one of them negative (a lone 0 among seconds is more likely a typo), are log2 stops,
// most likely (HDR-HexPlane's -3, -1, 1): one problem, against the first file
// with a non-positive one, says so with the fix. Returns whether it did.
bool ReportStopsLikeExposures(const SceneFiles& scene,
                              const DatasetLoadOptions& options,
                              ProblemSink& sink);
// A frame without `exposures` (or `time`, which nerfstudio's layout may leave out) in a scene
// whose other frames give one: a problem per such frame (it would be read as 1 s, or time 0,
// silently). A scene where no frame gives one (D-NeRF's exposures, a static capture) is fine.
void ReportMissingPerFrameKeys(const SceneFiles& scene, ProblemSink& sink);

// ---- dataset_layouts.cpp: which layout a folder is ----------------------------------------

// True when the folder has transforms_train.json or nerfstudio's transforms.json.
bool HasTransforms(const fs::path& root);
// A folder without them: HDR-GS's COLMAP layout is read (into report.dataset), others are
// named in a problem.
void CheckOtherLayout(const fs::path& root,
                      const DatasetLoadOptions& options,
                      ProblemSink& sink,
                      DatasetReport& report);
// nerfstudio's single transforms.json: only undistorted pinhole cameras can be rendered.
void CheckNerfstudioCameraModel(const json& doc, const Reader& r);
// Splits nerfstudio's one file: test_filenames / val_filenames when given, else every 8th
// frame (index % 8 == 0) is held out for test, the convention of the 3DGS evaluation.
void SplitNerfstudio(const fs::path& root,
                     const json& doc,
                     const Reader& r,
                     std::array<SplitFile, 3>& files);
// "nerfstudio", "hdrnerf", "hdr4d" (exposures given) or "dnerf".
std::string LayoutName(const SceneFiles& scene, const Dataset& dataset);

}  // namespace hdr4d::dataset_detail
