// The small parts of the dataset format: split names, frame access, problem text, image paths.
// Reading, layouts and checking are in dataset_reading.cpp, dataset_layouts.cpp and
// dataset_check.cpp (ARCHITECTURE §3).
#include "core/dataset/dataset.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string_view>

#include "core/util/error.h"

namespace hdr4d {
namespace fs = std::filesystem;

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

const char* ExposureUnitName(ExposureUnit unit) {
  return unit == ExposureUnit::kStops ? "stops" : "seconds";
}

ExposureUnit ParseExposureUnit(const std::string& name, const char* what) {
  for (ExposureUnit unit : {ExposureUnit::kSeconds, ExposureUnit::kStops}) {
    if (name == ExposureUnitName(unit)) return unit;
  }
  Fail("{}: unknown exposure unit '{}' (use seconds or stops)", what, name);
}

const char* const kExposureUnitHelp =
    "How the scene's `exposures` numbers are read: seconds (HDR-4DGS) or stops (log2, "
    "seconds = 2**value, as HDR-HexPlane's JSON gives them)";

ExposureUnit RecordedExposureUnit(const nlohmann::json& config, const std::string& config_path) {
  if (!config.is_object()) return ExposureUnit::kSeconds;  // the caller reports the file
  const auto it = config.find("exposure_unit");
  if (it == config.end()) return ExposureUnit::kSeconds;  // a run from before the key
  if (it->is_string()) {
    for (ExposureUnit unit : {ExposureUnit::kSeconds, ExposureUnit::kStops}) {
      if (it->get<std::string>() == ExposureUnitName(unit)) return unit;
    }
  }
  Fail("{}: exposure_unit: expected \"seconds\" or \"stops\", got {}", config_path, it->dump());
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

}  // namespace hdr4d
