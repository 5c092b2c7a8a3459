#include "datagen/scene_presets.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/util/error.h"

namespace hdr4d::datagen {

namespace {

struct PresetSize {
  const char* name;
  int width;
  int samples;
  int points;
};

// ci: tiny and noisy but every code path runs; mini: the benchmark's default; paper: Table 8.
constexpr PresetSize kPresetSizes[] = {
    {"ci", 48, 8, 2000},
    {"mini", 200, 64, 20000},
    {"paper", 800, 128, 100000},
};

// ci renders few frames: 5 + 1 timestamps for a moving camera, 2 + 1 for at most 3 cameras.
constexpr int kCiMonocularTrain = 5, kCiMonocularTest = 1;
constexpr int kCiMultiViewTrain = 2, kCiMultiViewTest = 1, kCiMaxCameras = 3;

}  // namespace

const char* RigName(Rig rig) { return rig == Rig::kMonocular ? "monocular" : "multiview"; }

const char* ExposurePatternName(ExposurePattern pattern) {
  switch (pattern) {
    case ExposurePattern::kCycleOverTime:
      return "cycle_over_time";
    case ExposurePattern::kEveryExposure:
      return "every_exposure";
    case ExposurePattern::kCycleOverViews:
      return "cycle_over_views";
  }
  return "?";
}

const std::vector<SceneInfo>& AllScenes() {
  using enum Rig;
  using enum ExposurePattern;
  static const std::vector<SceneInfo> scenes = {
      {"airplane", kMonocular, kCycleOverTime, 1, 280, 70, 40, 10, true, 1.0, 0,
       "a plane circles an airfield at sunset: banking flight, flexing wings (shape key), a "
       "spinning propeller, a blinking beacon, a sinking, reddening sun"},
      {"deer", kMonocular, kCycleOverTime, 1, 80, 20, 16, 4, true, 1.0, 0,
       "a deer (armature-skinned) walks from under a barn roof into the sun; the lantern dims"},
      {"lego", kMonocular, kCycleOverTime, 1, 240, 60, 32, 8, true, 1.0, 0,
       "a toy excavator rolls and digs, its flag waves (Wave modifier); the work light cycles "
       "colour, the cab beacon pulses and the headlights switch on"},
      {"tank", kMonocular, kCycleOverTime, 1, 136, 34, 24, 6, true, 1.0, 0,
       "a tank leaves a wall's shadow, traverses its turret, ripples its tracks (Wave modifier) "
       "and fires twice (muzzle flashes); a floodlight flickers"},
      {"hook", kMultiView, kEveryExposure, 10, 28, 4, 14, 2, true, 1.0, 0,
       "a boxer (armature) throws hook punches at a swinging bag under a swinging lamp"},
      {"jump", kMultiView, kEveryExposure, 10, 21, 3, 14, 2, true, 1.0, 0,
       "jumping jacks (armature) under three spot lights whose colours rotate, inside a neon "
       "ring that changes colour"},
      {"mutant", kMultiView, kCycleOverViews, 3, 135, 14, 27, 3, true, 1.0, 0,
       "a hulking creature (armature + swelling shape key) lumbers from shadow into a spot "
       "light, its eyes glowing ever brighter, by a flickering wall torch"},
      {"standup", kMultiView, kEveryExposure, 5, 51, 8, 14, 2, true, 1.0, 0,
       "a figure (armature) rises from a stool into a bright overhead beam; a desk lamp warms "
       "up"},
      {"studio", kMultiView, kEveryExposure, 9, 24, 0, 12, 0, false, 1.0, 0,
       "a ball rolls past a swaying, bending post under a small bare bulb that dims to a fifth "
       "(saturated at every exposure) while a spot light ramps up 20x; 8 ring cameras at two "
       "heights, a 9th held out between two of them and lower; a concave camera response",
       /*held_out_cameras=*/1, /*crf=*/"naka-rushton:0.2,2.2", /*noise=*/false},
      {"room", kMultiView, kEveryExposure, 6, 24, 0, 8, 0, false, 0.75, 0,
       "a figure waves and a ball rolls through a room of non-repeating texture (floor, three "
       "walls, crates) that COLMAP can match, under a bare bulb (saturated at every exposure) "
       "and a spot light sweeping the floor; made for rig calibration (datagen --capture)",
       /*held_out_cameras=*/1},
      {"marker", kMonocular, kCycleOverTime, 1, 5, 1, 5, 1, false, 0.75, 64,
       "camera-convention check: a small emissive ball on black visiting every image quadrant "
       "(render_info.json holds its centre per render)"},
  };
  return scenes;
}

std::vector<std::string> DefaultSceneNames() {
  std::vector<std::string> names;
  for (const SceneInfo& s : AllScenes()) {
    if (s.in_all) names.push_back(s.name);
  }
  return names;
}

const SceneInfo& FindScene(const std::string& name) {
  std::string known;
  for (const SceneInfo& s : AllScenes()) {
    if (s.name == name) return s;
    known += (known.empty() ? "" : ", ") + s.name;
  }
  Fail("datagen: unknown scene '{}' (known: {}, or all)", name, known);
}

const std::vector<std::string>& PresetNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const PresetSize& p : kPresetSizes) n.push_back(p.name);
    return n;
  }();
  return names;
}

ScenePreset ResolvePreset(const std::string& scene, const std::string& preset, int width) {
  const SceneInfo& info = FindScene(scene);
  const PresetSize* size = nullptr;
  for (const PresetSize& p : kPresetSizes) {
    if (preset == p.name) size = &p;
  }
  if (size == nullptr) Fail("datagen: unknown preset '{}' (known: ci, mini, paper)", preset);

  ScenePreset out;
  out.scene = info.name;
  out.preset = size->name;
  out.rig = info.rig;
  out.exposure_pattern = info.exposure_pattern;
  out.cameras = info.cameras;
  out.held_out_cameras = info.held_out_cameras;
  if (width < 0) Fail("datagen: the image width must be positive, got {}", width);
  out.width = width > 0 ? width : size->width;
  out.height = std::max(1, static_cast<int>(std::lround(out.width * info.aspect)));
  out.samples = std::max(size->samples, info.min_samples);
  out.points = size->points;
  if (out.preset == "paper") {
    out.train_timestamps = info.paper_train;
    out.test_timestamps = info.paper_test;
  } else if (out.preset == "mini") {
    out.train_timestamps = info.mini_train;
    out.test_timestamps = info.mini_test;
  } else if (info.rig == Rig::kMonocular) {
    out.train_timestamps = kCiMonocularTrain;
    out.test_timestamps = kCiMonocularTest;
  } else if (info.held_out_cameras > 0) {  // the held-out cameras are the test split
    out.train_timestamps = kCiMultiViewTrain + kCiMultiViewTest;
    out.test_timestamps = 0;
    out.cameras = std::min(out.cameras - info.held_out_cameras, kCiMaxCameras) +
                  info.held_out_cameras;
  } else {
    out.train_timestamps = kCiMultiViewTrain;
    out.test_timestamps = kCiMultiViewTest;
    out.cameras = std::min(out.cameras, kCiMaxCameras);
  }
  return out;
}

std::vector<int> TestTimeIndices(int total, int count) {
  HDR4D_CHECK(count >= 0 && count <= total);
  std::vector<int> indices;
  for (int j = 0; j < count; ++j) {
    // Integer form of floor((j + 0.5) * total / count): exact, so the pattern never drifts.
    indices.push_back(static_cast<int>((static_cast<long long>(2 * j + 1) * total) / (2 * count)));
  }
  return indices;
}

std::vector<double> PointSampleTimes(const ScenePreset& preset) {
  const int slices = std::clamp(preset.timestamps(), 1, kMaxPointTimes);
  std::vector<double> times;
  for (int k = 0; k < slices; ++k) times.push_back((k + 0.5) / slices);
  return times;
}

std::vector<PlannedRender> PlanRenders(const ScenePreset& preset) {
  const int total = preset.timestamps();
  HDR4D_CHECK(total >= 2 && preset.cameras >= 1);
  HDR4D_CHECK(preset.held_out_cameras >= 0 && preset.held_out_cameras < preset.cameras);
  const int first_held_out = preset.cameras - preset.held_out_cameras;
  const std::vector<int> test = TestTimeIndices(total, preset.test_timestamps);
  const int num_exposures = static_cast<int>(preset.exposures.size());
  std::vector<PlannedRender> renders;
  for (int i = 0; i < total; ++i) {
    const bool is_test = std::binary_search(test.begin(), test.end(), i);
    for (int c = 0; c < preset.cameras; ++c) {
      PlannedRender r;
      r.hdr_file = fmt::format("hdr/cam{:02d}_t{:04d}.exr", c, i);
      r.camera_id = c;
      r.time_index = i;
      r.time = static_cast<double>(i) / (total - 1);
      r.split = is_test || c >= first_held_out ? Split::kTest : Split::kTrain;
      switch (preset.exposure_pattern) {
        case ExposurePattern::kCycleOverTime:
          r.exposure_indices = {i % num_exposures};
          break;
        case ExposurePattern::kCycleOverViews:
          r.exposure_indices = {(c + i) % num_exposures};
          break;
        case ExposurePattern::kEveryExposure:
          for (int k = 0; k < num_exposures; ++k) r.exposure_indices.push_back(k);
          break;
      }
      renders.push_back(std::move(r));
    }
  }
  return renders;
}

std::string LdrFileName(const PlannedRender& render, int exposure_index) {
  return fmt::format("images/cam{:02d}_t{:04d}_e{}.png", render.camera_id, render.time_index,
                     exposure_index);
}

}  // namespace hdr4d::datagen
