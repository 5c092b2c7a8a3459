#include "core/dataset.h"

#include "core/colmap_layout.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <string_view>
#include <tuple>

#include "core/dataset_image_rules.h"
#include "core/error.h"
#include "core/file_access.h"
#include "core/image_io.h"
#include "core/json_util.h"
#include "core/output_guard.h"
#include "core/parallel.h"
#include "core/ply.h"
#include "core/progress.h"

namespace hdr4d {
namespace fs = std::filesystem;
using nlohmann::json;

const char* SplitName(Split split) {
  switch (split) {
    case Split::kTrain:
      return "train";
    case Split::kTest:
      return "test";
    case Split::kVal:
      return "val";
  }
  return "?";
}

Split ParseSplit(const std::string& name, const char* what) {
  for (Split split : {Split::kTrain, Split::kTest, Split::kVal}) {
    if (name == SplitName(split)) return split;
  }
  Fail("{}: unknown split '{}' (use train, test or val)", what, name);
}

std::vector<const Frame*> Dataset::AllFrames() const {
  std::vector<const Frame*> frames;
  frames.reserve(NumFrames());
  for (const std::vector<Frame>* split : {&train, &test, &val}) {
    for (const Frame& f : *split) frames.push_back(&f);
  }
  return frames;
}

const std::vector<Frame>& Dataset::FramesOf(Split split) const {
  switch (split) {
    case Split::kTrain:
      return train;
    case Split::kTest:
      return test;
    case Split::kVal:
      return val;
  }
  return train;
}

std::string DatasetProblem::ToString() const {
  std::string s = file.string();
  if (frame >= 0) s += fmt::format(": frame {}", frame);
  if (!key.empty()) s += ": " + key;
  return s + ": " + message;
}

fs::path ResolveImagePath(const fs::path& root, const std::string& file_path) {
  static constexpr std::string_view kImageExtensions[] = {".png", ".jpg",  ".jpeg", ".exr", ".hdr",
                                                          ".tif", ".tiff", ".bmp",  ".webp"};
  fs::path relative(file_path);
  std::string ext = relative.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  const bool known = std::find(std::begin(kImageExtensions), std::end(kImageExtensions), ext) !=
                     std::end(kImageExtensions);
  if (!known) relative += ".png";
  return (root / relative).lexically_normal();
}

namespace {

// Where each kind of file sorts in a report: the root itself first, then per split the
// transforms file and its HDR-NeRF exposure file, then the point cloud.
enum FileRank { kRankRoot = 0, kRankPointCloud = 100 };
int SplitRank(Split split, bool exposure_file) {
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
std::string WithoutPathPrefix(const std::string& message, const fs::path& path) {
  const std::string prefix = path.string() + ": ";
  return message.rfind(prefix, 0) == 0 ? message.substr(prefix.size()) : message;
}

// A short preview of a bad value for a problem line (never the whole value: it may be huge).
std::string Describe(const json& value) { return JsonPreview(value, 40); }

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
};

struct SplitFile {
  Split split = Split::kTrain;
  fs::path path;
  bool parsed = false;
  std::optional<double> camera_angle_x;
  std::optional<double> near, far;
  std::vector<PendingFrame> frames;
};

// The frame's pose; identity when missing or ill-shaped (the problem is recorded).
Eigen::Matrix4d ParseMatrix(const Reader& r, const json& obj, int frame) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  const auto it = obj.find("transform_matrix");
  if (it == obj.end()) {
    r.Problem(frame, "transform_matrix", "missing");
    return m;
  }
  const json& rows = *it;
  bool shape_ok = rows.is_array() && rows.size() == 4;
  for (std::size_t i = 0; shape_ok && i < 4; ++i) {
    shape_ok = rows[i].is_array() && rows[i].size() == 4;
    for (std::size_t j = 0; shape_ok && j < 4; ++j) {
      shape_ok = rows[i][j].is_number();
      if (shape_ok) m(i, j) = rows[i][j].get<double>();
    }
  }
  if (!shape_ok) {
    r.Problem(frame, "transform_matrix", "expected a 4x4 array of numbers, got " + Describe(rows));
    return Eigen::Matrix4d::Identity();
  }
  if (std::string problem = PoseProblem(m); !problem.empty()) {
    r.Problem(frame, "transform_matrix", problem);
  }
  return m;
}

// HDR-NeRF: exposure_<split>.json maps "<file_path>_<k>.png" to the exposure time.
struct ExposureTable {
  Reader reader;  // problems name the exposure file, the view's frame index and the image name
  json values;
};

// Parses one transforms file into pending frames (images are checked later).
void ParseSplitFile(const fs::path& root,
                    SplitFile& file,
                    const json& doc,
                    const Reader& r,
                    const ExposureTable* hdrnerf,
                    bool time_optional = false) {
  if (!doc.is_object()) {
    r.Problem(-1, "", "expected a JSON object at the top level, got " + Describe(doc));
    return;
  }
  file.camera_angle_x = r.Number(doc, -1, "camera_angle_x");
  if (file.camera_angle_x &&
      !(*file.camera_angle_x > 0 && *file.camera_angle_x < std::numbers::pi)) {
    r.Problem(-1, "camera_angle_x",
              fmt::format("{} radians is not in (0, pi)", *file.camera_angle_x));
    file.camera_angle_x.reset();
  }
  file.near = r.Number(doc, -1, "near");
  file.far = r.Number(doc, -1, "far");
  IntrinsicsKeys top;
  top.Read(r, doc, -1);

  const auto frames_it = doc.find("frames");
  if (frames_it == doc.end()) {
    r.Problem(-1, "frames", "missing");
    return;
  }
  if (!frames_it->is_array()) {
    r.Problem(-1, "frames", "expected an array, got " + Describe(*frames_it));
    return;
  }
  // An empty test or val split is legitimate (a capture without held-out views); an empty
  // training set is not.
  if (frames_it->empty() && file.split == Split::kTrain) r.Problem(-1, "frames", "no frames");
  file.parsed = true;

  const int rank = SplitRank(file.split, false);
  bool camera_angle_reported = false;
  for (std::size_t i = 0; i < frames_it->size(); ++i) {
    const int index = static_cast<int>(i);
    const json& obj = (*frames_it)[i];
    if (!obj.is_object()) {
      r.Problem(index, "", "expected a JSON object, got " + Describe(obj));
      continue;
    }
    PendingFrame pending;
    pending.rank = rank;
    pending.json_path = file.path;
    Frame& f = pending.frame;
    f.split = file.split;
    f.index = index;

    if (obj.contains("file_path")) {
      if (std::optional<std::string> path = r.String(obj, index, "file_path")) f.file_path = *path;
    } else {
      r.Problem(index, "file_path", "missing");
    }
    f.camera.world_from_cam_gl = ParseMatrix(r, obj, index);

    if (obj.contains("time")) {
      if (std::optional<double> t = r.Number(obj, index, "time")) {
        if (*t < 0) {
          r.Problem(index, "time", fmt::format("must not be negative, got {}", *t));
        } else {
          f.time_raw = *t;
        }
      }
    } else if (hdrnerf == nullptr && !time_optional) {
      r.Problem(index, "time", "missing (every frame needs a time)");
    }

    if (const auto it = obj.find("exposures"); it != obj.end()) {
      // The reference reads a scalar; a one-element list is the same value.
      const json* value = &*it;
      if (it->is_array() && it->size() == 1) value = &(*it)[0];
      if (!value->is_number()) {
        r.Problem(index, "exposures", "expected a number (seconds), got " + Describe(*it));
      } else {
        const double e = value->get<double>();
        if (!(std::isfinite(e) && e > 0)) {
          r.Problem(index, "exposures", fmt::format("must be positive and finite, got {}", e));
        } else {
          f.exposure = e;
          f.exposure_given = true;
        }
      }
    }
    if (std::optional<std::string> exr = r.String(obj, index, "exr_file_path")) {
      f.exr_file_path = *exr;
      f.hdr_path = (root / *exr).lexically_normal();
    }
    f.camera_id = r.Int(obj, index, "camera_id", 0).value_or(-1);
    f.exposure_index = r.Int(obj, index, "exposure_index", 0).value_or(-1);
    IntrinsicsKeys keys;
    keys.Read(r, obj, index);
    pending.keys = keys.Over(top);
    if (!pending.keys.fl_x && !file.camera_angle_x && !camera_angle_reported) {
      r.Problem(-1, "camera_angle_x",
                fmt::format("missing, and frame {} gives no fl_x either (one of them is required)",
                            index));
      camera_angle_reported = true;
    }

    if (hdrnerf == nullptr) {
      if (!f.file_path.empty()) f.image_path = ResolveImagePath(root, f.file_path);
      file.frames.push_back(std::move(pending));
      continue;
    }
    // HDR-NeRF: one frame per exposure of this view, "<file_path>_<k>.png" for k = 0, 1, ...
    if (f.file_path.empty()) continue;
    int k = 0;
    for (;; ++k) {
      const std::string name = fmt::format("{}_{}.png", f.file_path, k);
      const auto it = hdrnerf->values.find(name);
      if (it == hdrnerf->values.end()) break;
      PendingFrame view = pending;
      view.frame.file_path = name;
      view.frame.image_path = (root / name).lexically_normal();
      view.frame.exposure_index = k;
      view.frame.exposure_given = true;
      if (!it->is_number() || !(std::isfinite(it->get<double>()) && it->get<double>() > 0)) {
        hdrnerf->reader.Problem(index, name, "expected a positive exposure, got " + Describe(*it));
      } else {
        view.frame.exposure = it->get<double>();
      }
      file.frames.push_back(std::move(view));
    }
    if (k == 0) {
      hdrnerf->reader.Problem(index, f.file_path + "_0.png", "missing: no exposure for this view");
    }
  }
}

struct ImageResult {
  std::optional<ImageSpecInfo> ldr, hdr;
  std::string ldr_error, hdr_error;
};

// Reads one image as deeply as `check` says and applies the rules of its role (LDR file_path or
// HDR exr_file_path, core/dataset_image_rules.h): what training would refuse is found here.
ImageSpecInfo Inspect(const fs::path& path, ImageCheck check, bool hdr) {
  ImageSpecInfo spec;
  std::string problem;
  if (check == ImageCheck::kFull) {
    const Image image = ReadImage(path);  // rejects NaN/Inf pixels
    spec = {image.width(), image.height(), image.channels(),
            image.encoding() == Encoding::kLinear};
    problem = hdr ? HdrImageProblem(image) : LdrImageProblem(image);
  } else {
    spec = ReadImageSpec(path);
    problem = hdr ? HdrImageHeaderProblem(spec) : LdrImageHeaderProblem(spec);
  }
  if (!problem.empty()) Fail("{}: {}", path.string(), problem);
  return spec;
}

// Smaller scenes check in well under a second: a bar would only be noise.
constexpr std::size_t kProgressMinFrames = 200;

void CheckImages(std::vector<PendingFrame*>& frames,
                 const DatasetLoadOptions& options,
                 std::vector<ImageResult>& results) {
  results.assign(frames.size(), {});
  std::unique_ptr<Progress> progress;
  if (options.show_progress && frames.size() >= kProgressMinFrames) {
    progress = std::make_unique<Progress>("check images", static_cast<std::int64_t>(frames.size()));
  }
  ParallelFor(static_cast<std::int64_t>(frames.size()), 1, [&](std::int64_t i) {
    const Frame& f = frames[i]->frame;
    ImageResult& result = results[i];
    if (!f.image_path.empty()) {
      try {
        result.ldr = Inspect(f.image_path, options.image_check, /*hdr=*/false);
      } catch (const std::exception& e) {
        result.ldr_error = e.what();
      }
    }
    if (f.hdr_path) {
      try {
        result.hdr = Inspect(*f.hdr_path, options.image_check, /*hdr=*/true);
      } catch (const std::exception& e) {
        result.hdr_error = e.what();
      }
    }
    if (progress) progress->Advance();
  });
  if (progress) progress->Finish();
}

std::string SizeString(int w, int h) { return fmt::format("{}x{}", w, h); }

// nerfstudio's single transforms.json: only undistorted pinhole cameras can be rendered.
void CheckNerfstudioCameraModel(const json& doc, const Reader& r) {
  const auto it = doc.find("camera_model");
  if (it == doc.end()) return;
  if (!it->is_string()) {
    r.Problem(-1, "camera_model", "expected a string, got " + Describe(*it));
    return;
  }
  const std::string model = it->get<std::string>();
  if (model == "PINHOLE" || model == "SIMPLE_PINHOLE") return;
  if (model == "OPENCV") {
    for (const char* key : {"k1", "k2", "k3", "k4", "p1", "p2"}) {
      const auto k = doc.find(key);
      if (k != doc.end() && (!k->is_number() || k->get<double>() != 0.0)) {
        r.Problem(-1, key,
                  "lens distortion is not supported (hdr4d renders pinhole cameras); undistort "
                  "the images first");
        return;
      }
    }
    return;
  }
  r.Problem(-1, "camera_model",
            fmt::format("'{}' is not supported (hdr4d renders pinhole cameras); use PINHOLE or "
                        "undistort the images first",
                        model));
}

// Splits nerfstudio's one file: test_filenames / val_filenames when given, else every 8th
// frame (index % 8 == 0) is held out for test, the convention of the 3DGS evaluation.
void SplitNerfstudio(const fs::path& root,
                     const json& doc,
                     const Reader& r,
                     std::array<SplitFile, 3>& files) {
  std::map<fs::path, Split> listed;
  bool any_list = false;
  for (const auto& [key, split] :
       {std::pair{"test_filenames", Split::kTest}, std::pair{"val_filenames", Split::kVal},
        std::pair{"train_filenames", Split::kTrain}}) {
    const auto it = doc.find(key);
    if (it == doc.end()) continue;
    any_list = true;
    if (!it->is_array()) {
      r.Problem(-1, key, "expected a list of file paths, got " + Describe(*it));
      continue;
    }
    for (const json& name : *it) {
      if (!name.is_string()) {
        r.Problem(-1, key, "expected file path strings, got " + Describe(name));
        continue;
      }
      listed.emplace(ResolveImagePath(root, name.get<std::string>()), split);
    }
  }
  std::vector<PendingFrame> all = std::move(files[0].frames);
  files[0].frames.clear();
  for (PendingFrame& p : all) {
    Split split = Split::kTrain;
    if (any_list) {
      const auto it = listed.find(p.frame.image_path);
      if (it != listed.end()) split = it->second;
    } else if (p.frame.index % 8 == 0) {
      split = Split::kTest;
    }
    p.frame.split = split;
    files[static_cast<int>(split)].frames.push_back(std::move(p));
  }
  for (int s = 1; s < 3; ++s) {
    files[s].camera_angle_x = files[0].camera_angle_x;
    files[s].near = files[0].near;
    files[s].far = files[0].far;
    files[s].parsed = true;
  }
}

// The files a scene is made of and the folders holding its images are inputs of whatever read
// it: no writer of this process may replace them or add files among the images
// (core/output_guard.h), so renders never land on or beside ground truth.
void ProtectScene(const Dataset& dataset, const std::vector<fs::path>& json_files) {
  const std::string scene = dataset.root.string();
  const std::string file_role =
      fmt::format("a file of dataset {} (a command never overwrites its inputs)", scene);
  const std::string image_role =
      fmt::format("an image of dataset {} (ground truth is never overwritten)", scene);
  for (const fs::path& f : json_files) ProtectInputFile(f, file_role);
  if (dataset.point_cloud_path) ProtectInputFile(*dataset.point_cloud_path, file_role);
  std::set<fs::path> folders;
  for (const Frame* f : dataset.AllFrames()) {
    for (const std::optional<fs::path>& path :
         {f->image_path.empty() ? std::nullopt : std::optional<fs::path>(f->image_path),
          f->hdr_path}) {
      if (!path) continue;
      ProtectInputFile(*path, image_role);
      folders.insert(path->parent_path());
    }
  }
  for (const fs::path& folder : folders) {
    ProtectInputFolder(folder, fmt::format("the images of dataset {} (write outputs elsewhere)",
                                           scene));
  }
}

}  // namespace

DatasetReport CheckDataset(const fs::path& root, const DatasetLoadOptions& options) {
  DatasetReport report;
  ProblemSink sink;
  std::error_code ec;
  // "folder not found" only when nothing is there: an unreadable folder says so.
  if (std::string problem = InputFolderProblem(root); !problem.empty()) {
    if (ProbePath(root).kind == PathKind::kFile || ProbePath(root).kind == PathKind::kOther)
      problem = "not a folder (a dataset is a folder with transforms_*.json)";
    sink.Add(kRankRoot, root, -1, "", problem);
    report.problems = sink.Sorted();
    return report;
  }

  const fs::path train_path = root / "transforms_train.json";
  const fs::path nerfstudio_path = root / "transforms.json";
  const bool nerfstudio = !fs::exists(train_path, ec) && fs::exists(nerfstudio_path, ec);
  if (!fs::exists(train_path, ec) && !nerfstudio) {
    if (IsHdrGsColmapLayout(root)) {
      try {
        report.dataset = ReadHdrGsColmapLayout(root);
        if (options.image_check != ImageCheck::kNone)
          for (const Frame* f : report.dataset->AllFrames()) {
            const ImageSpecInfo spec = ReadImageSpec(f->image_path);
            if (spec.width != f->camera.intrinsics.width || spec.height != f->camera.intrinsics.height)
              sink.Add(kRankRoot, f->image_path, -1, "",
                       fmt::format("size {}x{} differs from the COLMAP camera's {}x{}", spec.width,
                                   spec.height, f->camera.intrinsics.width, f->camera.intrinsics.height));
          }
      } catch (const std::exception& e) {
        sink.Add(kRankRoot, root, -1, "", e.what());
      }
    } else if (fs::is_directory(root / "sparse", ec)) {
      sink.Add(kRankRoot, root, -1, "",
               "a COLMAP layout needs images/ beside sparse/ (as in HDR-GS's synthetic scenes)");
    } else if (fs::exists(root / "poses_bounds_exps.npy", ec)) {
      sink.Add(kRankRoot, root, -1, "",
               "an LLFF layout (poses_bounds_exps.npy, as in HDR-NeRF real scenes) is not "
               "supported yet; convert it to transforms_{train,test}.json");
    } else {
      sink.Add(SplitRank(Split::kTrain, false), train_path, -1, "", "file not found");
    }
    report.problems = sink.Sorted();
    return report;
  }

  const bool hdrnerf = !nerfstudio && fs::exists(root / "exposure_train.json", ec);
  std::optional<fs::path> nerfstudio_ply;  // its `ply_file_path`
  std::array<SplitFile, 3> files;
  std::vector<fs::path> json_files;  // every JSON file of the scene that was read
  const Split splits[3] = {Split::kTrain, Split::kTest, Split::kVal};
  for (int s = 0; s < 3; ++s) {
    SplitFile& file = files[s];
    file.split = splits[s];
    file.path = root / fmt::format("transforms_{}.json", SplitName(file.split));
    if (nerfstudio) {
      if (s > 0) continue;  // one file holds every split
      file.path = nerfstudio_path;
    }
    const Reader r(sink, SplitRank(file.split, false), file.path);
    if (!fs::exists(file.path, ec)) {
      if (file.split == Split::kTest && options.require_test) r.Problem(-1, "", "file not found");
      continue;
    }
    json_files.push_back(file.path);
    json doc;
    try {
      doc = ReadJsonFile(file.path);
    } catch (const std::exception& e) {  // also nlohmann's number overflow (1e999)
      r.Problem(-1, "", WithoutPathPrefix(e.what(), file.path));
      continue;
    }
    std::optional<ExposureTable> table;
    if (hdrnerf) {
      const fs::path exposure_path = root / fmt::format("exposure_{}.json", SplitName(file.split));
      const Reader er(sink, SplitRank(file.split, true), exposure_path);
      json_files.push_back(exposure_path);
      try {
        table.emplace(ExposureTable{er, ReadJsonFile(exposure_path)});
        if (!table->values.is_object()) {
          er.Problem(-1, "", "expected an object mapping image names to exposures");
          table.reset();
        }
      } catch (const std::exception& e) {
        er.Problem(-1, "", WithoutPathPrefix(e.what(), exposure_path));
      }
      if (!table) continue;
    }
    ParseSplitFile(root, file, doc, r, table ? &*table : nullptr, nerfstudio);
    if (nerfstudio && file.parsed) {
      CheckNerfstudioCameraModel(doc, r);
      SplitNerfstudio(root, doc, r, files);
      if (const auto ply = r.String(doc, -1, "ply_file_path")) nerfstudio_ply = root / *ply;
    }
  }
  if (!files[0].parsed) {
    report.problems = sink.Sorted();
    return report;
  }

  std::vector<PendingFrame*> frames;
  for (SplitFile& file : files) {
    for (PendingFrame& p : file.frames) frames.push_back(&p);
  }

  // Images: every header (or every pixel) in parallel, problems reported in frame order.
  std::vector<ImageResult> images;
  bool probe_failed = false;  // kNone: reported once, not again for every unsized frame
  if (options.image_check != ImageCheck::kNone) {
    CheckImages(frames, options, images);
  } else {
    // Size the cameras that declare no w/h from one image: every frame shares its size.
    images.assign(frames.size(), {});
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const PendingFrame& p = *frames[i];
      if ((p.keys.w && p.keys.h) || p.frame.image_path.empty()) continue;
      std::string why;
      for (const std::optional<fs::path>& path :
           {std::optional<fs::path>(p.frame.image_path), p.frame.hdr_path}) {
        if (!path) continue;
        try {
          images[i].ldr = ReadImageSpec(*path);
          break;
        } catch (const std::exception& e) {
          if (why.empty()) why = e.what();
        }
      }
      if (!images[i].ldr) {
        sink.Add(p.rank, p.json_path, p.frame.index, "file_path",
                 fmt::format("cannot size the camera (no w/h given): {}", why));
        probe_failed = true;
        frames[i]->image_ok = false;
      }
      break;
    }
  }

  // The size every image must have: the most common LDR size (ties: the first seen), so one
  // odd image is the one reported, whichever frame it is.
  std::optional<std::pair<int, int>> reference_size;
  std::string reference_name;
  {
    std::map<std::pair<int, int>, std::pair<int, std::size_t>> counts;  // size -> (count, first)
    for (std::size_t i = 0; i < frames.size(); ++i) {
      if (!images[i].ldr) continue;
      auto [it, inserted] = counts.try_emplace({images[i].ldr->width, images[i].ldr->height}, 0, i);
      ++it->second.first;
    }
    std::size_t first = 0;
    int best = 0;
    for (const auto& [size, count_first] : counts) {
      const auto [count, first_index] = count_first;
      if (count > best || (count == best && first_index < first)) {
        best = count;
        first = first_index;
        reference_size = size;
      }
    }
    if (reference_size) {
      reference_name = fmt::format("frame {} of {}", frames[first]->frame.index,
                                   frames[first]->json_path.filename().string());
    }
  }
  for (std::size_t i = 0; i < frames.size(); ++i) {
    PendingFrame& p = *frames[i];
    const ImageResult& img = images[i];
    const Frame& f = p.frame;
    auto add = [&](const char* key, std::string message) {
      sink.Add(p.rank, p.json_path, f.index, key, std::move(message));
      p.image_ok = false;
    };
    if (!img.ldr_error.empty()) add("file_path", img.ldr_error);
    if (!img.hdr_error.empty()) add("exr_file_path", img.hdr_error);
    // Expected size: declared, else the reference.
    std::optional<std::pair<int, int>> expected = reference_size;
    if (p.keys.w || p.keys.h) {
      const int w = p.keys.w.value_or(reference_size ? reference_size->first : 0);
      const int h = p.keys.h.value_or(reference_size ? reference_size->second : 0);
      expected = {w, h};
      if (img.ldr && (img.ldr->width != w || img.ldr->height != h)) {
        add("file_path",
            fmt::format("{}: image is {}, but w, h declare {}", f.image_path.string(),
                        SizeString(img.ldr->width, img.ldr->height), SizeString(w, h)));
        expected.reset();
      }
    } else if (img.ldr && reference_size &&
               (img.ldr->width != reference_size->first ||
                img.ldr->height != reference_size->second)) {
      add("file_path",
          fmt::format("{}: image is {}, but most images are {} (e.g. {}); every image must have "
                      "the same size",
                      f.image_path.string(), SizeString(img.ldr->width, img.ldr->height),
                      SizeString(reference_size->first, reference_size->second), reference_name));
    }
    if (img.hdr) {
      if (img.ldr && (img.hdr->width != img.ldr->width || img.hdr->height != img.ldr->height)) {
        add("exr_file_path",
            fmt::format("{}: HDR image is {}, its LDR image {} is {}", f.hdr_path->string(),
                        SizeString(img.hdr->width, img.hdr->height), f.image_path.string(),
                        SizeString(img.ldr->width, img.ldr->height)));
      } else if (!img.ldr && expected &&
                 (img.hdr->width != expected->first || img.hdr->height != expected->second)) {
        add("exr_file_path", fmt::format("{}: HDR image is {}, expected {}", f.hdr_path->string(),
                                         SizeString(img.hdr->width, img.hdr->height),
                                         SizeString(expected->first, expected->second)));
      }
    }
  }

  // Cameras: intrinsics from the keys, the file's camera_angle_x and the image size.
  for (std::size_t i = 0; i < frames.size(); ++i) {
    PendingFrame& p = *frames[i];
    Frame& f = p.frame;
    const SplitFile& file = files[static_cast<int>(f.split)];
    int w = p.keys.w.value_or(0), h = p.keys.h.value_or(0);
    const ImageSpecInfo* size = images[i].ldr ? &*images[i].ldr : nullptr;
    if (!size && reference_size && options.image_check == ImageCheck::kNone) {
      w = w ? w : reference_size->first;
      h = h ? h : reference_size->second;
    } else if (size) {
      w = w ? w : size->width;
      h = h ? h : size->height;
    }
    if (w <= 0 || h <= 0) {
      if (p.image_ok && !probe_failed && !f.image_path.empty()) {
        sink.Add(p.rank, p.json_path, f.index, "w",
                 "image size unknown: declare w and h or provide the image");
      }
      continue;
    }
    PinholeIntrinsics& k = f.camera.intrinsics;
    k.width = w;
    k.height = h;
    if (p.keys.fl_x) {
      k.fx = *p.keys.fl_x;
    } else if (file.camera_angle_x) {
      k.fx = PinholeIntrinsics::FromFovX(*file.camera_angle_x, w, h).fx;
    } else {
      continue;  // reported once per file while parsing
    }
    k.fy = p.keys.fl_y.value_or(k.fx);
    k.cx = p.keys.cx.value_or(0.5 * w);
    k.cy = p.keys.cy.value_or(0.5 * h);
    if (std::string problem = k.Problem(); !problem.empty()) {
      sink.Add(p.rank, p.json_path, f.index, "fl_x", problem);
    }
  }

  // Duplicate images within a split.
  for (const SplitFile& file : files) {
    std::map<fs::path, int> seen;
    for (const PendingFrame& p : file.frames) {
      if (p.frame.image_path.empty()) continue;
      const auto [it, inserted] = seen.emplace(p.frame.image_path, p.frame.index);
      if (!inserted) {
        sink.Add(p.rank, p.json_path, p.frame.index, "file_path",
                 fmt::format("{} is already used by frame {} of this file",
                             p.frame.image_path.string(), it->second));
      }
    }
  }

  // Times: normalised by the largest over every split (or per file, as the reference does).
  Dataset dataset;
  dataset.root = root;
  double global_max = 0;
  for (const PendingFrame* p : frames) global_max = std::max(global_max, p->frame.time_raw);
  dataset.time_max_raw = global_max;
  for (SplitFile& file : files) {
    double file_max = 0;
    for (const PendingFrame& p : file.frames) file_max = std::max(file_max, p.frame.time_raw);
    const double divisor =
        options.time_normalisation == TimeNormalisation::kGlobal ? global_max : file_max;
    for (PendingFrame& p : file.frames) {
      p.frame.time = divisor > 1 ? p.frame.time_raw / divisor : p.frame.time_raw;
    }
  }

  for (SplitFile& file : files) {
    std::vector<Frame>& out = file.split == Split::kTrain  ? dataset.train
                              : file.split == Split::kTest ? dataset.test
                                                           : dataset.val;
    out.reserve(file.frames.size());
    for (PendingFrame& p : file.frames) out.push_back(std::move(p.frame));
  }
  dataset.near = files[0].near;
  dataset.far = files[0].far;
  if (files[0].camera_angle_x) {
    dataset.camera_angle_x = *files[0].camera_angle_x;
  } else if (!dataset.train.empty() && dataset.train[0].camera.intrinsics.fx > 0) {
    dataset.camera_angle_x = dataset.train[0].camera.intrinsics.FovX();
  }
  const bool any_exposure = std::any_of(dataset.train.begin(), dataset.train.end(),
                                        [](const Frame& f) { return f.exposure_given; }) ||
                            std::any_of(dataset.test.begin(), dataset.test.end(),
                                        [](const Frame& f) { return f.exposure_given; }) ||
                            std::any_of(dataset.val.begin(), dataset.val.end(),
                                        [](const Frame& f) { return f.exposure_given; });
  dataset.layout = nerfstudio     ? "nerfstudio"
                   : hdrnerf      ? "hdrnerf"
                   : any_exposure ? "hdr4d"
                                  : "dnerf";

  const fs::path ply_path = nerfstudio_ply.value_or(root / "point3d.ply");
  if (nerfstudio_ply && !fs::exists(ply_path, ec)) {
    sink.Add(SplitRank(Split::kTrain, false), nerfstudio_path, -1, "ply_file_path",
             ply_path.string() + " not found");
  } else if (fs::exists(ply_path, ec)) {
    dataset.point_cloud_path = ply_path;
    try {
      report.point_cloud_points = static_cast<std::int64_t>(ReadPly(ply_path).size());
    } catch (const Error& e) {
      sink.Add(kRankPointCloud, ply_path, -1, "", WithoutPathPrefix(e.what(), ply_path));
    }
  }

  if (options.protect_inputs) ProtectScene(dataset, json_files);
  report.dataset = std::move(dataset);
  report.problems = sink.Sorted();
  return report;
}

Dataset LoadDataset(const fs::path& root, const DatasetLoadOptions& options) {
  DatasetReport report = CheckDataset(root, options);
  if (report.problems.empty()) {
    HDR4D_CHECK(report.dataset.has_value());
    return std::move(*report.dataset);
  }
  // One line, as every user-facing error: the first problem, and where to see the rest.
  std::string message = report.problems.front().ToString();
  if (report.problems.size() > 1) {
    message += fmt::format(" (and {} more problem{}: run `hdr4d dataset check {}` for all)",
                           report.problems.size() - 1, report.problems.size() == 2 ? "" : "s",
                           root.string());
  }
  throw Error(message);
}

}  // namespace hdr4d
