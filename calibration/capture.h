// The capture layout `hdr4d calibrate` reads (README "Calibrating a rig"):
//   static/<camera>/<image>        the empty scene from each rig camera (one or more images)
//   static/extra/<image>           optional hand-held images that help COLMAP (then dropped)
//   sequence/<camera>/<frame>_<k>.<ext>   bracket k of each frame (JPEG, PNG, 16-bit TIFF)
//   exposures.json (optional)      {"brackets": [t0, t1, ...]} for every camera, and/or
//                                  {"<camera>/<file>": seconds} per image; else EXIF ExposureTime
//   timestamps.json (optional)     {"<frame>": seconds} for every frame; else frame / --fps
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace hdr4d {

struct CaptureFrame {
  int index = 0;                                   // <frame> in the file name
  std::vector<std::filesystem::path> brackets;     // by k
  std::vector<double> exposures;                   // seconds, by k
  std::optional<double> time;                      // seconds, from timestamps.json
};

struct CaptureCamera {
  std::string name;                                 // the folder name
  std::vector<std::filesystem::path> static_images; // may be empty for --stage radiometry
  std::vector<CaptureFrame> frames;                 // sorted by index
};

struct Capture {
  std::filesystem::path root;
  std::vector<CaptureCamera> cameras;                // sorted by name
  std::vector<std::filesystem::path> extra_images;  // static/extra
  int brackets_per_frame = 0;
  std::vector<std::string> warnings;
};

// Scans and checks a capture. Throws hdr4d::Error (one line naming the camera, frame and file)
// for: no sequence folder or cameras, a static/<camera> without sequence/<camera>, a file name
// that is not <frame>_<k>, a frame with missing or extra brackets, a frame missing for one
// camera, an image without an exposure time, and brackets of one frame with equal exposure
// times. A bracket whose exposure differs from the
// same bracket of other frames is a warning (auto-exposure may have moved).
// With need_sequence = false (`--stage geometry`) a capture without sequence/ is accepted and its
// cameras are the folders of static/ other than extra/.
Capture ScanCapture(const std::filesystem::path& root, bool need_sequence = true);

}  // namespace hdr4d
