// The scenes `hdr4d datagen` renders and their presets, mirroring HDR-4D-Syn (the HDR-4DGS
// paper's appendix, Table 8): four monocular scenes (one camera moving around the scene, one
// render per timestamp, exposures cycling 0.125 / 2 / 32 s over time) and four multi-view scenes
// (fixed cameras, every camera at every timestamp). The `paper` preset reproduces Table 8's
// counts; `mini` is the benchmark's default; `ci` renders in seconds.
//
// Table 8 in short (train / test, Frames = timestamps):
//   airplane 280/70, deer 80/20, lego 240/60, tank 136/34     1 camera, 1 exposure per frame
//   hook 28/4 x 10 cameras, jump 21/3 x 10, standup 51/8 x 5   every exposure per render
//   mutant 135/14 x 3 cameras                                  one exposure per render (its LDR
//                                                              count equals its HDR count)
// Test timestamps are spread evenly through the sequence (every 5th for the monocular scenes)
// and every camera renders them; train and test never share a timestamp.
#pragma once

#include <string>
#include <vector>

#include "core/dataset/dataset.h"

namespace hdr4d::datagen {

enum class Rig { kMonocular, kMultiView };
const char* RigName(Rig rig);  // "monocular", "multiview"

// Which of the exposures (0.125, 2, 32 s) each render (camera c, timestamp i) gets.
enum class ExposurePattern {
  kCycleOverTime,   // one: i mod 3 (the monocular scenes)
  kEveryExposure,   // all three (hook, jump, standup)
  kCycleOverViews,  // one: (c + i) mod 3 (mutant)
};
const char* ExposurePatternName(ExposurePattern pattern);

// HDR-4D-Syn's exposure times in seconds.
inline const std::vector<double> kSynExposures = {0.125, 2.0, 32.0};
// D-NeRF's and HDR-4D-Syn's horizontal field of view (radians).
inline constexpr double kSynCameraAngleX = 0.6911112070083618;

struct SceneInfo {
  std::string name;
  Rig rig = Rig::kMonocular;
  ExposurePattern exposure_pattern = ExposurePattern::kCycleOverTime;
  int cameras = 1;                      // at the paper and mini presets
  int paper_train = 0, paper_test = 0;  // timestamps (Table 8's Frames)
  int mini_train = 0, mini_test = 0;    // timestamps at the mini preset
  bool in_all = true;                   // rendered by --scene all
  double aspect = 1.0;                  // height / width
  int min_samples = 0;                  // Cycles samples at least this (the marker)
  std::string description;
  // Cameras held out for testing at every timestamp (the last ones): a novel-view split, where
  // the eight scenes hold out timestamps instead.
  int held_out_cameras = 0;
  // The scene's own LDR synthesis defaults (DatagenOptions' flags win): camera response spec
  // and whether it adds sensor noise.
  std::string crf = "filmic";
  bool noise = true;
};

// The eight HDR-4D-Syn-style scenes, then `marker` (a camera-convention check, not in "all").
const std::vector<SceneInfo>& AllScenes();
// Names rendered by --scene all, in Table 8's order.
std::vector<std::string> DefaultSceneNames();
// Throws hdr4d::Error naming the unknown scene and listing the known ones.
const SceneInfo& FindScene(const std::string& name);

const std::vector<std::string>& PresetNames();  // ci, mini, paper

// Everything a render of one scene at one preset needs.
struct ScenePreset {
  std::string scene, preset;
  Rig rig = Rig::kMonocular;
  ExposurePattern exposure_pattern = ExposurePattern::kCycleOverTime;
  int cameras = 1;           // including the held-out ones
  int held_out_cameras = 0;  // the last cameras: test views at every timestamp
  int train_timestamps = 0, test_timestamps = 0;
  int width = 0, height = 0;
  int samples = 0;  // Cycles samples per pixel
  int points = 0;   // point3d.ply size
  double camera_angle_x = kSynCameraAngleX;
  std::vector<double> exposures = kSynExposures;
  // Where the script puts the fixed cameras: "scene" (the scene's ring or arc) or "capture"
  // (datagen --capture: an arc of neighbours 30 degrees apart, see render_scene.py).
  std::string layout = "scene";
  int extra_views = 0;  // a capture's hand-held static views (static/extra/), after the cameras
  int timestamps() const { return train_timestamps + test_timestamps; }
};

// Throws hdr4d::Error for an unknown scene or preset (naming it and the known ones). width > 0
// replaces the preset's image width (the height follows the scene's aspect).
ScenePreset ResolvePreset(const std::string& scene, const std::string& preset, int width = 0);

// `count` test timestamps out of `total`, spread evenly: floor((j + 1/2) total / count). Sorted,
// distinct, inside [0, total). Requires 0 <= count <= total.
std::vector<int> TestTimeIndices(int total, int count);

struct PlannedRender {
  std::string hdr_file;  // relative to the scene root: hdr/camCC_tTTTT.exr
  int camera_id = 0;
  int time_index = 0;
  double time = 0;  // time_index / (timestamps - 1), in [0, 1]
  Split split = Split::kTrain;
  std::vector<int> exposure_indices;  // into ScenePreset::exposures
  // A capture's static image (datagen --capture): the scene at t = 0 with its actors hidden,
  // the empty scene a rig is calibrated on. Not part of any dataset split.
  bool still = false;
};

// The times point3d.ply's surfaces are sampled at (issue 56): the midpoints of min(timestamps,
// kMaxPointTimes) equal slices of [0, 1], each strictly inside (0, 1) as the official HDR-4DGS
// loader needs when it subsamples a cloud (it keeps only 0 < t < 1), and spread over the
// scene's time so that every Gaussian does not start at t = 0. One time, 0.5, for one timestamp.
inline constexpr int kMaxPointTimes = 8;
std::vector<double> PointSampleTimes(const ScenePreset& preset);

// Every render of a scene, ordered by time, then camera. A held-out camera's renders are test
// views at every timestamp; the other cameras' are test views at the test timestamps.
std::vector<PlannedRender> PlanRenders(const ScenePreset& preset);

// images/camCC_tTTTT_eK.png: the LDR image of a render at exposure index K.
std::string LdrFileName(const PlannedRender& render, int exposure_index);

}  // namespace hdr4d::datagen
