// The transforms files of a scene read key by key, every problem recorded against its file,
// frame and key (ARCHITECTURE §3).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/geometry/camera.h"
#include "core/dataset/dataset_detail.h"
#include "core/files/json_util.h"

namespace hdr4d::dataset_detail {
namespace {

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

// A frame's `exposures` number in `unit`: seconds must be positive, stops (seconds = 2**value)
// finite and within +-kMaxStops. The number is kept as written either way.
void ReadExposure(const Reader& r, int index, double value, ExposureUnit unit, Frame& f,
                  const std::string& key = "exposures") {
  f.exposure_written = value;
  if (unit == ExposureUnit::kStops) {
    if (!(std::isfinite(value) && std::abs(value) <= kMaxStops)) {
      r.Problem(index, key,
                fmt::format("{} stops is not a finite number within +-{:g}", value, kMaxStops));
      return;
    }
    f.exposure = std::exp2(value);
  } else if (!(std::isfinite(value) && value > 0)) {
    r.Problem(index, key, fmt::format("must be positive and finite, got {}", value));
    return;
  } else {
    f.exposure = value;
  }
  f.exposure_given = true;
}

// One frame's keys, over the file's top-level intrinsics; HDR-NeRF's exposures come later.
PendingFrame ParseFrame(const fs::path& root,
                        const SplitFile& file,
                        const json& obj,
                        int index,
                        const Reader& r,
                        const IntrinsicsKeys& top,
                        bool time_required,
                        ExposureUnit unit,
                        bool* camera_angle_reported) {
  PendingFrame pending;
  pending.rank = SplitRank(file.split, false);
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
    pending.time_key = true;
    if (std::optional<double> t = r.Number(obj, index, "time")) {
      if (*t < 0) {
        r.Problem(index, "time", fmt::format("must not be negative, got {}", *t));
      } else {
        f.time_raw = *t;
      }
    }
  } else if (time_required) {
    r.Problem(index, "time", "missing (every frame needs a time)");
  }

  if (const auto it = obj.find("exposures"); it != obj.end()) {
    pending.exposure_key = true;
    // The reference reads a scalar; a one-element list is the same value.
    const json* value = &*it;
    if (it->is_array() && it->size() == 1) value = &(*it)[0];
    if (!value->is_number()) {
      r.Problem(index, "exposures",
                fmt::format("expected a number ({}), got {}", ExposureUnitName(unit),
                            Describe(*it)));
    } else {
      ReadExposure(r, index, value->get<double>(), unit, f);
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
  if (!pending.keys.fl_x && !file.camera_angle_x && !*camera_angle_reported) {
    r.Problem(
        -1, "camera_angle_x",
        fmt::format("missing, and frame {} gives no fl_x either (one of them is required)", index));
    *camera_angle_reported = true;
  }
  return pending;
}

// HDR-NeRF: one frame per exposure of this view, "<file_path>_<k>.png" for k = 0, 1, ...
// The largest k of the exposure file's "<stem>_<k>.png" entries, or -1.
int LastExposureIndex(const ExposureTable& hdrnerf, const std::string& stem) {
  int last = -1;
  const std::string prefix = stem + "_";
  for (const auto& [name, value] : hdrnerf.values.items()) {
    if (name.rfind(prefix, 0) != 0 || name.size() <= prefix.size() + 4) continue;
    const std::string k = name.substr(prefix.size(), name.size() - prefix.size() - 4);
    if (name.compare(name.size() - 4, 4, ".png") != 0 ||
        k.find_first_not_of("0123456789") != std::string::npos || k.size() > 6)
      continue;
    last = std::max(last, std::stoi(k));
  }
  return last;
}

void AddHdrNerfViews(const fs::path& root,
                     const PendingFrame& pending,
                     int index,
                     const ExposureTable& hdrnerf,
                     ExposureUnit unit,
                     SplitFile& file) {
  const Frame& f = pending.frame;
  if (f.file_path.empty()) return;
  int k = 0;
  for (;; ++k) {
    const std::string name = fmt::format("{}_{}.png", f.file_path, k);
    const auto it = hdrnerf.values.find(name);
    if (it == hdrnerf.values.end()) break;
    PendingFrame view = pending;
    view.frame.file_path = name;
    view.frame.image_path = (root / name).lexically_normal();
    view.frame.exposure_index = k;
    if (!it->is_number()) {
      hdrnerf.reader.Problem(index, name, "expected a positive exposure, got " + Describe(*it));
    } else {
      ReadExposure(hdrnerf.reader, index, it->get<double>(), unit, view.frame, name);
    }
    file.frames.push_back(std::move(view));
  }
  if (k == 0) {
    hdrnerf.reader.Problem(index, f.file_path + "_0.png", "missing: no exposure for this view");
  } else if (const int last = LastExposureIndex(hdrnerf, f.file_path); last > k) {
    // The views are read up to the first gap: the later ones would be dropped silently.
    hdrnerf.reader.Problem(index, fmt::format("{}_{}.png", f.file_path, k),
                           fmt::format("missing, while {}_{}.png is given: exposure indices "
                                       "must run from 0 without a gap",
                                       f.file_path, last));
  }
}

}  // namespace

std::string Describe(const json& value) { return JsonPreview(value, 40); }

// Parses one transforms file into pending frames (images are checked later).
void ParseSplitFile(const fs::path& root,
                    SplitFile& file,
                    const json& doc,
                    const Reader& r,
                    const ExposureTable* hdrnerf,
                    bool time_optional,
                    ExposureUnit unit) {
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

  bool camera_angle_reported = false;
  const bool time_required = hdrnerf == nullptr && !time_optional;
  for (std::size_t i = 0; i < frames_it->size(); ++i) {
    const int index = static_cast<int>(i);
    const json& obj = (*frames_it)[i];
    if (!obj.is_object()) {
      r.Problem(index, "", "expected a JSON object, got " + Describe(obj));
      continue;
    }
    PendingFrame pending =
        ParseFrame(root, file, obj, index, r, top, time_required, unit, &camera_angle_reported);
    if (hdrnerf != nullptr) {
      AddHdrNerfViews(root, pending, index, *hdrnerf, unit, file);
      continue;
    }
    Frame& f = pending.frame;
    if (!f.file_path.empty()) f.image_path = ResolveImagePath(root, f.file_path);
    file.frames.push_back(std::move(pending));
  }
}

SceneFiles ReadSceneFiles(const fs::path& root,
                          const DatasetLoadOptions& options,
                          ProblemSink& sink) {
  SceneFiles scene;
  std::error_code ec;
  const fs::path nerfstudio_path = root / "transforms.json";
  scene.nerfstudio =
      !fs::exists(root / "transforms_train.json", ec) && fs::exists(nerfstudio_path, ec);
  scene.hdrnerf = !scene.nerfstudio && fs::exists(root / "exposure_train.json", ec);
  const bool nerfstudio = scene.nerfstudio, hdrnerf = scene.hdrnerf;
  std::array<SplitFile, 3>& files = scene.files;
  std::vector<fs::path>& json_files = scene.json_files;
  std::optional<fs::path>& nerfstudio_ply = scene.nerfstudio_ply;
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
    ParseSplitFile(root, file, doc, r, table ? &*table : nullptr, nerfstudio,
                   options.exposure_unit);
    if (nerfstudio && file.parsed) {
      CheckNerfstudioCameraModel(doc, r);
      SplitNerfstudio(root, doc, r, files);
      if (const auto ply = r.String(doc, -1, "ply_file_path")) nerfstudio_ply = root / *ply;
    }
  }
  return scene;
}

bool ReportStopsLikeExposures(const SceneFiles& scene,
                              const DatasetLoadOptions& options,
                              ProblemSink& sink) {
  if (options.exposure_unit != ExposureUnit::kSeconds) return false;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  int count = 0, non_positive = 0, negative = 0;
  const SplitFile* first = nullptr;  // the first file with a non-positive exposure
  for (const SplitFile& file : scene.files) {
    for (const PendingFrame& p : file.frames) {
      if (!p.frame.exposure_written) continue;
      const double v = *p.frame.exposure_written;
      if (!(std::abs(v) <= kStopsLookLimit)) return false;  // also NaN
      lo = std::min(lo, v), hi = std::max(hi, v), ++count;
      negative += v < 0;
      if (v <= 0) {
        ++non_positive;
        if (first == nullptr) first = &file;
      }
    }
  }
  if (first == nullptr || negative == 0) return false;  // a lone 0 is more likely a typo
  const Reader r(sink, SplitRank(first->split, false), first->path);
  r.Problem(-1, "exposures",
            fmt::format("all {} exposures are small (in [{:g}, {:g}]) and {} not positive: "
                        "they look like log2 stops (HDR-HexPlane writes -3, -1, 1), not "
                        "seconds; read them with --exposure-unit stops (seconds = 2**value: "
                        "{:g} -> {:g} s, {:g} -> {:g} s)",
                        count, lo, hi, non_positive, lo, std::exp2(lo), hi, std::exp2(hi)));
  return true;
}

namespace {

// One key's check for ReportMissingPerFrameKeys: `has` tells whether a frame's JSON has it.
void ReportMissingKey(const SceneFiles& scene, ProblemSink& sink, const char* key,
                      bool (*has)(const PendingFrame&), const char* read_as) {
  int with = 0, total = 0;
  for (const SplitFile& file : scene.files)
    for (const PendingFrame& p : file.frames) with += has(p), ++total;
  if (with == 0 || with == total) return;
  const std::string problem = fmt::format(
      "missing, while {} of the scene's {} frames give one (it would be read as {})", with, total,
      read_as);
  for (const SplitFile& file : scene.files)
    for (const PendingFrame& p : file.frames)
      if (!has(p)) Reader(sink, p.rank, p.json_path).Problem(p.frame.index, key, problem);
}

}  // namespace

void ReportMissingPerFrameKeys(const SceneFiles& scene, ProblemSink& sink) {
  // HDR-NeRF's exposures come from its exposure files, checked there.
  if (!scene.hdrnerf)
    ReportMissingKey(scene, sink, "exposures", [](const PendingFrame& p) { return p.exposure_key; },
                     "1 s");
  // The native layout requires a time on every frame (its own problem); the others may go without.
  if (scene.nerfstudio || scene.hdrnerf)
    ReportMissingKey(scene, sink, "time", [](const PendingFrame& p) { return p.time_key; },
                     "time 0");
}

}  // namespace hdr4d::dataset_detail
