#include "calibration/capture.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <regex>
#include <set>

#include "core/image/image_io.h"
#include "core/util/error.h"
#include "core/files/json_util.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

std::vector<fs::path> ImagesIn(const fs::path& folder) {
  std::vector<fs::path> images;
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return images;
  for (const auto& entry : fs::directory_iterator(folder))
    if (entry.is_regular_file() && IsImagePath(entry.path())) images.push_back(entry.path());
  std::sort(images.begin(), images.end());
  return images;
}

std::vector<std::string> SubfoldersOf(const fs::path& folder) {
  std::vector<std::string> names;
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return names;
  for (const auto& entry : fs::directory_iterator(folder))
    if (entry.is_directory()) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

struct Sidecar {
  std::vector<double> brackets;
  std::map<std::string, double> per_image;
};

Sidecar ReadSidecar(const fs::path& path) {
  Sidecar sidecar;
  std::error_code ec;
  if (!fs::exists(path, ec)) return sidecar;
  const nlohmann::json doc = ReadJsonFile(path);
  if (!doc.is_object()) Fail("{}: expected an object", path.string());
  for (const auto& [key, value] : doc.items()) {
    if (key == "brackets") {
      if (!value.is_array()) Fail("{}: brackets: expected an array of seconds", path.string());
      for (const auto& t : value) {
        if (!t.is_number() || !(t.get<double>() > 0))
          Fail("{}: brackets: {} is not a positive exposure time", path.string(), t.dump());
        sidecar.brackets.push_back(t.get<double>());
      }
    } else {
      if (!value.is_number() || !(value.get<double>() > 0))
        Fail("{}: {}: {} is not a positive exposure time", path.string(), key, value.dump());
      sidecar.per_image[key] = value.get<double>();
    }
  }
  return sidecar;
}

// --stage geometry without sequence/: the cameras are static/'s folders other than extra/.
Capture StaticOnlyCapture(const fs::path& root) {
  Capture capture;
  capture.root = root;
  for (const std::string& name : SubfoldersOf(root / "static"))
    if (name != "extra") {
      CaptureCamera camera;
      camera.name = name;
      camera.static_images = ImagesIn(root / "static" / name);
      capture.cameras.push_back(std::move(camera));
    }
  if (capture.cameras.empty())
    Fail("{}: no camera folders (expected static/<camera>/<image>)", (root / "static").string());
  capture.extra_images = ImagesIn(root / "static" / "extra");
  return capture;
}

// The exposure time of bracket `bracket` (file `file`): the sidecar's per-image entry, its
// per-bracket list, or the file's EXIF.
double ExposureOf(const Sidecar& sidecar, const std::string& camera, const fs::path& file, int bracket,
                  int frame) {
  if (auto it = sidecar.per_image.find(camera + "/" + file.filename().string()); it != sidecar.per_image.end())
    return it->second;
  if (bracket < static_cast<int>(sidecar.brackets.size())) return sidecar.brackets[bracket];
  if (auto exif = ReadExposureTime(file)) return *exif;
  Fail("{}: camera {}, frame {}: no exposure time (no EXIF ExposureTime and no entry in "
       "exposures.json)", file.string(), camera, frame);
}

CaptureFrame ReadFrame(const fs::path& folder, const std::string& name, int index,
                       const std::map<int, fs::path>& brackets, const Sidecar& sidecar) {
  CaptureFrame frame;
  frame.index = index;
  int k = 0;
  for (const auto& [bracket, file] : brackets) {
    if (bracket != k)
      Fail("{}: camera {}, frame {}: bracket {} is missing", folder.string(), name, index, k);
    ++k;
    frame.brackets.push_back(file);
    const double t = ExposureOf(sidecar, name, file, bracket, index);
    for (std::size_t j = 0; j < frame.exposures.size(); ++j)
      if (frame.exposures[j] == t)
        Fail("{}: camera {}, frame {}: brackets {} and {} have the same exposure time {} s",
             file.string(), name, index, j, bracket, t);
    frame.exposures.push_back(t);
  }
  return frame;
}

CaptureCamera ReadCamera(const fs::path& root, const std::string& name, const Sidecar& sidecar) {
  static const std::regex pattern(R"(^(\d+)_(\d+)$)");
  const fs::path folder = root / "sequence" / name;
  CaptureCamera camera;
  camera.name = name;
  camera.static_images = ImagesIn(root / "static" / name);
  std::map<int, std::map<int, fs::path>> frames;
  for (const fs::path& file : ImagesIn(folder)) {
    std::smatch m;
    const std::string stem = file.stem().string();
    if (!std::regex_match(stem, m, pattern))
      Fail("{}: camera {}: file name is not <frame>_<bracket>", file.string(), name);
    frames[std::stoi(m[1])][std::stoi(m[2])] = file;
  }
  if (frames.empty()) Fail("{}: camera {} has no images", folder.string(), name);
  for (const auto& [index, brackets] : frames) camera.frames.push_back(ReadFrame(folder, name, index, brackets, sidecar));
  return camera;
}

// Timestamps: every frame of every camera needs one when the sidecar is there.
void ReadTimestamps(const fs::path& root, Capture* capture) {
  std::error_code ec;
  const fs::path path = root / "timestamps.json";
  if (!fs::exists(path, ec)) return;
  const nlohmann::json doc = ReadJsonFile(path);
  if (!doc.is_object()) Fail("{}: expected an object mapping frame numbers to seconds", path.string());
  for (CaptureCamera& camera : capture->cameras)
    for (CaptureFrame& frame : camera.frames) {
      const auto it = doc.find(std::to_string(frame.index));
      if (it == doc.end()) Fail("{}: frame {} (camera {}) has no timestamp", path.string(), frame.index, camera.name);
      if (!it->is_number() || !std::isfinite(it->get<double>()) || it->get<double>() < 0)
        Fail("{}: frame {}: {} is not a time in seconds >= 0", path.string(), frame.index, it->dump());
      frame.time = it->get<double>();
    }
}

// Every camera shows the same frames with the same number of brackets.
void CheckFramesAgree(const fs::path& sequence, Capture* capture) {
  const CaptureCamera& first = capture->cameras.front();
  capture->brackets_per_frame = static_cast<int>(first.frames.front().brackets.size());
  if (capture->brackets_per_frame < 2)
    Fail("{}: camera {}, frame {}: {} bracket; HDR fusion needs at least two",
         (sequence / first.name).string(), first.name, first.frames.front().index,
         capture->brackets_per_frame);
  std::set<int> all_frames;
  for (const CaptureCamera& camera : capture->cameras)
    for (const CaptureFrame& frame : camera.frames) all_frames.insert(frame.index);
  for (const CaptureCamera& camera : capture->cameras) {
    std::set<int> have;
    for (const CaptureFrame& frame : camera.frames) {
      have.insert(frame.index);
      if (static_cast<int>(frame.brackets.size()) != capture->brackets_per_frame)
        Fail("{}: camera {}, frame {}: {} brackets, camera {} frame {} has {}",
             (sequence / camera.name).string(), camera.name, frame.index, frame.brackets.size(),
             first.name, first.frames.front().index, capture->brackets_per_frame);
      for (int k = 0; k < capture->brackets_per_frame; ++k) {
        const double t0 = camera.frames.front().exposures[k];
        if (std::abs(frame.exposures[k] - t0) > 1e-6 * t0)
          capture->warnings.push_back(fmt::format(
              "camera {}, frame {}: bracket {} was exposed {} s, frame {} {} s", camera.name,
              frame.index, k, frame.exposures[k], camera.frames.front().index, t0));
      }
    }
    for (int index : all_frames)
      if (!have.count(index))
        Fail("{}: camera {}: frame {} is missing (other cameras have it)",
             (sequence / camera.name).string(), camera.name, index);
  }
}

}  // namespace

Capture ScanCapture(const fs::path& root, bool need_sequence) {
  std::error_code ec;
  if (!fs::is_directory(root, ec)) Fail("{}: capture folder not found", root.string());
  const fs::path sequence = root / "sequence";
  const std::vector<std::string> names = SubfoldersOf(sequence);
  if (names.empty() && !need_sequence && !fs::exists(sequence, ec)) return StaticOnlyCapture(root);
  if (names.empty())
    Fail("{}: no camera folders (expected sequence/<camera>/<frame>_<k>.<ext>)", sequence.string());
  // A camera with static images but no sequence was left out of the calibration without a word.
  for (const std::string& name : SubfoldersOf(root / "static"))
    if (name != "extra" && !std::binary_search(names.begin(), names.end(), name))
      Fail("{}: no such folder, but {} holds camera {}'s static images; every rig camera needs "
           "both (sequence cameras: {}; hand-held views go in static/extra/)",
           (sequence / name).string(), (root / "static" / name).string(), name,
           fmt::join(names, ", "));
  Capture capture;
  capture.root = root;
  const Sidecar sidecar = ReadSidecar(root / "exposures.json");
  for (const std::string& name : names) capture.cameras.push_back(ReadCamera(root, name, sidecar));
  capture.extra_images = ImagesIn(root / "static" / "extra");
  ReadTimestamps(root, &capture);
  CheckFramesAgree(sequence, &capture);
  return capture;
}

}  // namespace hdr4d
