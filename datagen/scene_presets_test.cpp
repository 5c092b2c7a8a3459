#include "datagen/scene_presets.h"

#include <gtest/gtest.h>

#include <map>
#include <set>

#include "tests/testing.h"

namespace hdr4d::datagen {
namespace {

using testing::ErrorOf;

struct Counts {
  int frames = 0, hdr = 0, ldr = 0;
  bool operator==(const Counts&) const = default;
};

Counts CountSplit(const std::vector<PlannedRender>& renders, Split split) {
  std::set<int> times;
  Counts c;
  for (const PlannedRender& r : renders) {
    if (r.split != split) continue;
    times.insert(r.time_index);
    ++c.hdr;
    c.ldr += static_cast<int>(r.exposure_indices.size());
  }
  c.frames = static_cast<int>(times.size());
  return c;
}

TEST(ScenePresets, PaperPresetReproducesTable8) {
  // Table 8 of the paper: training frames/HDR/LDR, testing frames/HDR/LDR, cameras.
  const std::map<std::string, std::pair<Counts, Counts>> table = {
      {"airplane", {{280, 280, 280}, {70, 70, 70}}}, {"deer", {{80, 80, 80}, {20, 20, 20}}},
      {"hook", {{28, 280, 840}, {4, 40, 120}}},      {"jump", {{21, 210, 630}, {3, 30, 90}}},
      {"lego", {{240, 240, 240}, {60, 60, 60}}},     {"mutant", {{135, 405, 405}, {14, 42, 42}}},
      {"standup", {{51, 255, 765}, {8, 40, 120}}},   {"tank", {{136, 136, 136}, {34, 34, 34}}},
  };
  for (const auto& [scene, counts] : table) {
    SCOPED_TRACE(scene);
    const ScenePreset preset = ResolvePreset(scene, "paper");
    EXPECT_EQ(preset.width, 800);
    EXPECT_EQ(preset.height, 800);
    EXPECT_EQ(preset.exposures, (std::vector<double>{0.125, 2.0, 32.0}));
    const std::vector<PlannedRender> renders = PlanRenders(preset);
    EXPECT_EQ(CountSplit(renders, Split::kTrain), counts.first);
    EXPECT_EQ(CountSplit(renders, Split::kTest), counts.second);
  }
}

TEST(ScenePresets, DefaultScenesAreTheEightOfHdr4dSyn) {
  EXPECT_EQ(DefaultSceneNames(), (std::vector<std::string>{"airplane", "deer", "lego", "tank",
                                                           "hook", "jump", "mutant", "standup"}));
  int monocular = 0;
  for (const std::string& name : DefaultSceneNames()) {
    const SceneInfo& s = FindScene(name);
    if (s.rig == Rig::kMonocular) {
      ++monocular;
      EXPECT_EQ(s.cameras, 1);
    } else {
      EXPECT_GE(s.cameras, 3);
      EXPECT_LE(s.cameras, 10);
    }
  }
  EXPECT_EQ(monocular, 4);
  EXPECT_FALSE(FindScene("marker").in_all);
}

TEST(ScenePresets, TestTimestampsSpreadEvenlyAndNeverOverlapTrain) {
  EXPECT_EQ(TestTimeIndices(10, 2), (std::vector<int>{2, 7}));
  EXPECT_EQ(TestTimeIndices(32, 4), (std::vector<int>{4, 12, 20, 28}));
  EXPECT_TRUE(TestTimeIndices(5, 0).empty());
  // Monocular paper scenes hold out every 5th timestamp.
  const std::vector<int> airplane = TestTimeIndices(350, 70);
  for (std::size_t j = 0; j < airplane.size(); ++j) EXPECT_EQ(airplane[j], 2 + 5 * int(j));

  const std::vector<PlannedRender> renders = PlanRenders(ResolvePreset("hook", "mini"));
  std::set<int> train, test;
  for (const PlannedRender& r : renders)
    (r.split == Split::kTest ? test : train).insert(r.time_index);
  for (int t : test) EXPECT_EQ(train.count(t), 0u) << t;
  EXPECT_EQ(train.size() + test.size(), 16u);
}

TEST(ScenePresets, ExposurePatterns) {
  // Monocular: exposures cycle over time, so consecutive frames see 0.125, 2, 32 s in turn.
  const std::vector<PlannedRender> mono = PlanRenders(ResolvePreset("deer", "mini"));
  for (const PlannedRender& r : mono) {
    ASSERT_EQ(r.exposure_indices.size(), 1u);
    EXPECT_EQ(r.exposure_indices[0], r.time_index % 3);
  }
  // Mutant: one exposure per render, cycling over cameras too, so each timestamp has all three.
  const std::vector<PlannedRender> mutant = PlanRenders(ResolvePreset("mutant", "mini"));
  std::map<int, std::set<int>> per_time;
  for (const PlannedRender& r : mutant) {
    ASSERT_EQ(r.exposure_indices.size(), 1u);
    per_time[r.time_index].insert(r.exposure_indices[0]);
  }
  for (const auto& [t, exposures] : per_time) EXPECT_EQ(exposures.size(), 3u) << t;
  // Multi-view: every exposure at every camera and timestamp.
  for (const PlannedRender& r : PlanRenders(ResolvePreset("standup", "ci")))
    EXPECT_EQ(r.exposure_indices, (std::vector<int>{0, 1, 2}));
}

TEST(ScenePresets, TimesSpanZeroToOneAndNamesAreUnique) {
  const std::vector<PlannedRender> renders = PlanRenders(ResolvePreset("jump", "ci"));
  std::set<std::string> files;
  double t_min = 1, t_max = 0;
  for (const PlannedRender& r : renders) {
    EXPECT_TRUE(files.insert(r.hdr_file).second) << r.hdr_file;
    t_min = std::min(t_min, r.time);
    t_max = std::max(t_max, r.time);
  }
  EXPECT_EQ(t_min, 0.0);
  EXPECT_EQ(t_max, 1.0);
  EXPECT_EQ(renders.front().hdr_file, "hdr/cam00_t0000.exr");
  EXPECT_EQ(LdrFileName(renders[4], 2), "images/cam01_t0001_e2.png");
}

TEST(ScenePresets, CiIsTinyAndMarkerIsNotSquare) {
  const ScenePreset hook = ResolvePreset("hook", "ci");
  EXPECT_EQ(hook.cameras, 3);
  EXPECT_EQ(hook.timestamps(), 3);
  EXPECT_LE(hook.width, 64);
  const ScenePreset airplane = ResolvePreset("airplane", "ci");
  EXPECT_EQ(airplane.train_timestamps, 5);
  EXPECT_EQ(airplane.test_timestamps, 1);
  const ScenePreset marker = ResolvePreset("marker", "ci");
  EXPECT_NE(marker.width, marker.height);  // catches a vertical/horizontal field-of-view mix-up
  EXPECT_GE(marker.samples, 64);
}

// studio: a novel-view split. Its 9th camera is the test split at every timestamp and every
// exposure; the 8 ring cameras train at every timestamp.
TEST(ScenePresets, StudioHoldsOutACameraNotTimestamps) {
  const ScenePreset preset = ResolvePreset("studio", "mini", 96);
  EXPECT_EQ(preset.width, 96);
  EXPECT_EQ(preset.height, 96);
  EXPECT_EQ(preset.cameras, 9);
  EXPECT_EQ(preset.held_out_cameras, 1);
  EXPECT_EQ(preset.timestamps(), 12);
  EXPECT_FALSE(FindScene("studio").in_all);
  EXPECT_EQ(FindScene("studio").crf, "naka-rushton:0.2,2.2");
  const std::vector<PlannedRender> renders = PlanRenders(preset);
  std::set<int> test_cameras, train_times;
  for (const PlannedRender& r : renders) {
    EXPECT_EQ(r.exposure_indices, (std::vector<int>{0, 1, 2}));
    if (r.split == Split::kTest) {
      test_cameras.insert(r.camera_id);
    } else {
      train_times.insert(r.time_index);
    }
  }
  EXPECT_EQ(test_cameras, (std::set<int>{8}));
  EXPECT_EQ(train_times.size(), 12u);
  EXPECT_EQ(CountSplit(renders, Split::kTest), (Counts{12, 12, 36}));
  EXPECT_EQ(CountSplit(renders, Split::kTrain), (Counts{12, 96, 288}));
  // ci keeps the held-out camera and at most 3 ring cameras.
  const ScenePreset ci = ResolvePreset("studio", "ci");
  EXPECT_EQ(ci.cameras, 4);
  EXPECT_EQ(ci.held_out_cameras, 1);
  EXPECT_EQ(ci.test_timestamps, 0);
  EXPECT_EQ(CountSplit(PlanRenders(ci), Split::kTest).hdr, ci.timestamps());
  // A width override keeps the scene's aspect; a negative one is an error.
  EXPECT_EQ(ResolvePreset("marker", "ci", 100).height, 75);
  EXPECT_NE(ErrorOf([] { ResolvePreset("deer", "mini", -5); }).find("width"), std::string::npos);
}

TEST(ScenePresets, UnknownSceneOrPresetNamesTheKnownOnes) {
  const std::string scene = ErrorOf([] { ResolvePreset("dragon", "mini"); });
  EXPECT_NE(scene.find("unknown scene 'dragon'"), std::string::npos) << scene;
  EXPECT_NE(scene.find("airplane"), std::string::npos) << scene;
  const std::string preset = ErrorOf([] { ResolvePreset("deer", "huge"); });
  EXPECT_NE(preset.find("unknown preset 'huge'"), std::string::npos) << preset;
  EXPECT_NE(preset.find("mini"), std::string::npos) << preset;
}

// point3d.ply's sample times: inside (0, 1) (the official loader keeps only those when it
// subsamples), spread evenly, at most kMaxPointTimes of them, one for a single timestamp.
TEST(ScenePresets, PointSampleTimesAreInsideZeroOneAndSpread) {
  EXPECT_EQ(PointSampleTimes(ResolvePreset("deer", "mini")),
            (std::vector<double>{0.0625, 0.1875, 0.3125, 0.4375, 0.5625, 0.6875, 0.8125, 0.9375}));
  EXPECT_EQ(PointSampleTimes(ResolvePreset("standup", "ci")),
            (std::vector<double>{1 / 6.0, 0.5, 5 / 6.0}));  // 2 + 1 timestamps
  ScenePreset still = ResolvePreset("deer", "ci");
  still.train_timestamps = 1, still.test_timestamps = 0;
  EXPECT_EQ(PointSampleTimes(still), std::vector<double>{0.5});
  for (const std::string& scene : DefaultSceneNames()) {
    for (const char* preset : {"ci", "mini", "paper"}) {
      const std::vector<double> times = PointSampleTimes(ResolvePreset(scene, preset));
      ASSERT_FALSE(times.empty());
      EXPECT_LE(times.size(), static_cast<std::size_t>(kMaxPointTimes));
      for (double t : times) EXPECT_TRUE(t > 0 && t < 1) << scene << " " << preset << " " << t;
    }
  }
}

}  // namespace
}  // namespace hdr4d::datagen
