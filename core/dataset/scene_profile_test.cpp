#include "core/dataset/scene_profile.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace hdr4d {
namespace {

Eigen::Matrix4d PoseAtAngle(double angle) {
  return LookAtWorldFromCamGl({3 * std::cos(angle), 3 * std::sin(angle), 1}, {0, 0, 0},
                              Eigen::Vector3d::UnitZ());
}

Frame MakeFrame(
    Split split, double time, double exposure, double angle, bool hdr = false, int camera_id = -1) {
  Frame f;
  f.split = split;
  f.time = f.time_raw = time;
  f.exposure = exposure;
  f.exposure_given = true;
  f.camera = {PinholeIntrinsics::FromFovX(0.8, 32, 24), PoseAtAngle(angle)};
  f.camera_id = camera_id;
  if (hdr) f.hdr_path = "hdr.exr";
  return f;
}

// One camera moving around the scene, one frame per timestamp (D-NeRF style).
Dataset Monocular(int n, double exposure = 1.0) {
  Dataset d;
  for (int i = 0; i < n; ++i) {
    d.train.push_back(MakeFrame(Split::kTrain, i / double(n - 1), exposure, 0.3 * i));
  }
  d.test.push_back(MakeFrame(Split::kTest, 0.5, exposure, 2.0));
  return d;
}

// `cameras` fixed cameras, the last one held out for test, at `times` timestamps.
Dataset MultiView(int cameras, int times, bool with_ids) {
  Dataset d;
  for (int c = 0; c < cameras; ++c) {
    for (int t = 0; t < times; ++t) {
      const double time = times > 1 ? t / double(times - 1) : 0.0;
      Frame f = MakeFrame(c == cameras - 1 ? Split::kTest : Split::kTrain, time, 1.0, 1.1 * c,
                          false, with_ids ? c : -1);
      (c == cameras - 1 ? d.test : d.train).push_back(f);
    }
  }
  return d;
}

TEST(SceneProfile, StaticVersusDynamic) {
  Dataset still = MultiView(4, 1, false);
  const SceneProfile s = ProfileScene(still);
  EXPECT_FALSE(s.dynamic);
  EXPECT_EQ(s.num_timestamps, 1);
  EXPECT_EQ(s.time_min, 0.0);
  EXPECT_EQ(s.time_max, 0.0);
  EXPECT_NE(s.Describe().find("static: one timestamp (0): trains without the time axis"),
            std::string::npos)
      << s.Describe();

  const SceneProfile d = ProfileScene(Monocular(5));
  EXPECT_TRUE(d.dynamic);
  EXPECT_EQ(d.num_timestamps, 5);  // the test time 0.5 is one of the train times
  EXPECT_EQ(d.time_min, 0.0);
  EXPECT_EQ(d.time_max, 1.0);
  EXPECT_NE(d.Describe().find("dynamic: 5 timestamps in [0, 1]"), std::string::npos)
      << d.Describe();
}

TEST(SceneProfile, OneVersusSeveralExposures) {
  const SceneProfile one = ProfileScene(Monocular(4, 2.0));
  EXPECT_FALSE(one.multi_exposure);
  EXPECT_EQ(one.exposures, std::vector<double>{2.0});
  EXPECT_NE(one.Describe().find("single exposure (2 s)"), std::string::npos) << one.Describe();

  Dataset d = Monocular(6);
  const double exposures[3] = {32.0, 0.125, 2.0};
  for (std::size_t i = 0; i < d.train.size(); ++i) d.train[i].exposure = exposures[i % 3];
  d.test[0].exposure = 2.0 * (1 + 1e-12);  // float noise: the same exposure
  const SceneProfile several = ProfileScene(d);
  EXPECT_TRUE(several.multi_exposure);
  EXPECT_EQ(several.exposures, (std::vector<double>{0.125, 2.0, 32.0}));
  EXPECT_NE(several.Describe().find("multi-exposure: 3 exposures (0.125, 2, 32 s)"),
            std::string::npos)
      << several.Describe();
}

TEST(SceneProfile, HdrGroundTruthAllPartialOrNone) {
  Dataset d = Monocular(4);
  SceneProfile p = ProfileScene(d);
  EXPECT_FALSE(p.has_hdr_gt);
  EXPECT_FALSE(p.partial_hdr_gt);
  EXPECT_FALSE(p.hdr_gt_in_train);
  EXPECT_NE(p.Describe().find("no HDR ground truth: HDR loss and HDR metrics skipped"),
            std::string::npos);

  d.test[0].hdr_path = "t.exr";  // every test frame
  p = ProfileScene(d);
  EXPECT_TRUE(p.has_hdr_gt);
  EXPECT_FALSE(p.partial_hdr_gt);
  EXPECT_FALSE(p.hdr_gt_in_train);
  EXPECT_EQ(p.num_hdr_frames, 1);

  d.train[1].hdr_path = "a.exr";
  p = ProfileScene(d);
  EXPECT_TRUE(p.has_hdr_gt);
  EXPECT_TRUE(p.hdr_gt_in_train);
  EXPECT_NE(p.Describe().find("HDR loss on training frames"), std::string::npos);

  d.test.push_back(MakeFrame(Split::kTest, 0.25, 1.0, 2.5));  // a test frame without HDR
  p = ProfileScene(d);
  EXPECT_FALSE(p.has_hdr_gt);
  EXPECT_TRUE(p.partial_hdr_gt);
  EXPECT_EQ(p.num_hdr_frames, 2);
  EXPECT_NE(p.Describe().find("partial HDR ground truth (2 of 6 frames)"), std::string::npos)
      << p.Describe();
}

TEST(SceneProfile, MonocularVersusMultiView) {
  const SceneProfile mono = ProfileScene(Monocular(6));
  EXPECT_FALSE(mono.multi_view);
  EXPECT_EQ(mono.num_cameras, 7);  // every frame has its own pose
  EXPECT_NE(mono.Describe().find("monocular: one moving camera (7 distinct poses)"),
            std::string::npos);

  const SceneProfile rig = ProfileScene(MultiView(4, 5, false));
  EXPECT_TRUE(rig.multi_view);
  EXPECT_TRUE(rig.dynamic);
  EXPECT_EQ(rig.num_cameras, 4);  // distinct poses
  EXPECT_EQ(rig.num_frames, 20);
  EXPECT_NE(rig.Describe().find("multi-view: 4 cameras"), std::string::npos);

  const SceneProfile ids = ProfileScene(MultiView(3, 2, true));
  EXPECT_TRUE(ids.multi_view);
  EXPECT_EQ(ids.num_cameras, 3);  // distinct camera_id
}

TEST(SceneProfile, ExposureBracketsFromOneMovingCameraStayMonocular) {
  // At each instant the one camera takes 3 exposures from the same pose.
  Dataset d;
  for (int t = 0; t < 4; ++t) {
    for (double e : {0.125, 2.0, 32.0})
      d.train.push_back(MakeFrame(Split::kTrain, t / 3.0, e, 0.4 * t));
  }
  d.test.push_back(MakeFrame(Split::kTest, 0.0, 2.0, 0.0));  // same instant and pose as train 0
  const SceneProfile p = ProfileScene(d);
  EXPECT_FALSE(p.multi_view);
  EXPECT_EQ(p.num_cameras, 4);
  EXPECT_TRUE(p.multi_exposure);
  EXPECT_EQ(p.num_timestamps, 4);
}

TEST(SceneProfile, MultiViewWithIdsEvenWithoutSharedInstants) {
  // Two cameras with their own ids, never at the same instant: camera_id says multi-view.
  Dataset d = Monocular(4);
  for (std::size_t i = 0; i < d.train.size(); ++i) d.train[i].camera_id = static_cast<int>(i % 2);
  const SceneProfile p = ProfileScene(d);
  EXPECT_TRUE(p.multi_view);
  EXPECT_EQ(p.num_cameras, 2);
}

TEST(SceneProfile, ToJsonAndSize) {
  const SceneProfile p = ProfileScene(MultiView(3, 2, false));
  const nlohmann::json j = p.ToJson();
  EXPECT_EQ(j["dynamic"], true);
  EXPECT_EQ(j["multi_view"], true);
  EXPECT_EQ(j["num_cameras"], 3);
  EXPECT_EQ(j["num_timestamps"], 2);
  EXPECT_EQ(j["width"], 32);
  EXPECT_EQ(j["height"], 24);
  EXPECT_EQ(j["exposures"], nlohmann::json::array({1.0}));
  EXPECT_EQ(j["has_hdr_gt"], false);
  EXPECT_EQ(j["time_max"], 1.0);
  EXPECT_NE(p.Describe().find("resolution: 32x24, 6 frames"), std::string::npos);
}

TEST(SceneProfile, EmptyDataset) {
  const SceneProfile p = ProfileScene(Dataset{});
  EXPECT_EQ(p.num_frames, 0);
  EXPECT_FALSE(p.dynamic);
  EXPECT_EQ(p.Describe(), "empty: no frames\n");
}

}  // namespace
}  // namespace hdr4d
