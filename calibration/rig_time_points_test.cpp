// Rig-time points (issue 54): a synthetic four-camera rig whose COLMAP model has few, noisy
// points (no hand-held views) and a wrong starting focal length, plus the rig's own sequence
// times as features with known truth.
#include "calibration/rig_time_points.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <random>
#include <unistd.h>

#include "calibration/rig_geometry.h"
#include "calibration/synthetic_rig_test_util.h"
#include "core/util/error.h"

namespace hdr4d {
namespace {

constexpr int kW = 640, kH = 480, kCameras = 4;
constexpr double kF = 500;

struct TruthRig {
  std::vector<Eigen::Isometry3d> cam_from_world;
  std::vector<Eigen::Vector3d> centres;
};

// Four cameras on an arc 4 units from the origin, 20 degrees apart, looking at it.
TruthRig MakeRig() {
  TruthRig rig;
  for (int c = 0; c < kCameras; ++c) {
    const Eigen::Isometry3d t = CameraOnArc((c - 1.5) * 0.35, 4, 0.2 * c);
    rig.cam_from_world.push_back(t);
    rig.centres.push_back(-t.linear().transpose() * t.translation());
  }
  return rig;
}

// The true pixel of `x` in camera c (COLMAP's convention), or nothing outside the image.
std::optional<Eigen::Vector2d> Project(const TruthRig& rig, int c, const Eigen::Vector3d& x) {
  const Eigen::Vector3d q = rig.cam_from_world[c] * x;
  if (q.z() <= 0) return std::nullopt;
  const Eigen::Vector2d p(kF * q.x() / q.z() + kW / 2.0, kF * q.y() / q.z() + kH / 2.0);
  if (p.x() < 0 || p.y() < 0 || p.x() >= kW || p.y() >= kH) return std::nullopt;
  return p;
}

// COLMAP's model of the rig: the true poses, `points` points with `noise` px, a focal length of
// `colmap_f` (the truth is kF).
ColmapModel MakeModel(const TruthRig& rig, int points, double noise, double colmap_f) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::normal_distribution<double> n(0, noise);
  ColmapModel model;
  for (int c = 0; c < kCameras; ++c) {
    model.cameras[c + 1] = {c + 1, "RADIAL", kW, kH, {colmap_f, kW / 2.0, kH / 2.0, 0.0, 0.0}};
    ColmapImage& image = model.images[c + 1];
    image.id = image.camera_id = c + 1;
    image.name = fmt::format("cam{}/static.png", c);
    image.cam_from_world_rotation = Eigen::Quaterniond(rig.cam_from_world[c].linear());
    image.cam_from_world_translation = rig.cam_from_world[c].translation();
  }
  for (int id = 1; id <= points; ++id) {
    ColmapPoint p;
    p.id = id;
    p.xyz = Eigen::Vector3d(u(rng), u(rng), u(rng));
    for (int c = 0; c < kCameras; ++c) {
      const auto pixel = Project(rig, c, p.xyz);
      if (!pixel) continue;
      ColmapImage& image = model.images[c + 1];
      image.points2d.push_back(*pixel + Eigen::Vector2d(n(rng), n(rng)));
      image.point3d_ids.push_back(id);
      p.track.emplace_back(c + 1, static_cast<int>(image.points2d.size()) - 1);
    }
    if (p.track.size() >= 2) model.points[id] = p;
  }
  return model;
}

// One time of the rig's sequence: `points` scene points, each with its own random descriptor seen
// (with a little descriptor noise) by every camera it lands in, pixels with `noise` px.
RigTimeFeatures MakeTime(const TruthRig& rig, int points, double noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::uniform_real_distribution<float> d(0, 1);
  std::normal_distribution<double> n(0, noise);
  std::normal_distribution<float> dn(0, 0.02f);
  RigTimeFeatures time;
  time.label = fmt::format("frame {}", seed);
  time.views.resize(kCameras);
  for (int i = 0; i < points; ++i) {
    const Eigen::Vector3d x(u(rng), u(rng), u(rng));
    cv::Mat descriptor(1, 128, CV_32F);
    for (int k = 0; k < 128; ++k) descriptor.at<float>(0, k) = d(rng);
    for (int c = 0; c < kCameras; ++c) {
      const auto pixel = Project(rig, c, x);
      if (!pixel) continue;
      cv::Mat seen = descriptor.clone();
      for (int k = 0; k < 128; ++k) seen.at<float>(0, k) += dn(rng);
      time.views[c].pixels.push_back(*pixel + Eigen::Vector2d(n(rng), n(rng)));
      time.views[c].descriptors.push_back(seen);
    }
  }
  return time;
}

// Camera centres (COLMAP's world) of a calibrated rig: its normalisation undone.
std::vector<Eigen::Vector3d> Centres(const Rig& rig) {
  std::vector<Eigen::Vector3d> centres;
  for (const RigCamera& c : rig.cameras)
    centres.push_back(c.world_from_cam_gl.topRightCorner<3, 1>() / rig.scale + rig.centre);
  return centres;
}

// The largest centre error, relative to camera 0 and after the best scale, as a fraction of the
// rig's size (RMS distance of the true centres from their centroid).
double CentreError(const std::vector<Eigen::Vector3d>& got, const std::vector<Eigen::Vector3d>& truth) {
  double num = 0, den = 0;
  for (std::size_t c = 1; c < got.size(); ++c)
    num += (got[c] - got[0]).dot(truth[c] - truth[0]), den += (got[c] - got[0]).squaredNorm();
  const double s = num / den;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& t : truth) mean += t / static_cast<double>(truth.size());
  double size = 0, worst = 0;
  for (const auto& t : truth) size += (t - mean).squaredNorm() / static_cast<double>(truth.size());
  for (std::size_t c = 1; c < got.size(); ++c)
    worst = std::max(worst, (s * (got[c] - got[0]) - (truth[c] - truth[0])).norm());
  return worst / std::sqrt(size);
}

double FocalError(const Rig& rig) {
  double worst = 0;
  for (const RigCamera& c : rig.cameras) worst = std::max(worst, std::abs(c.intrinsics.f / kF - 1));
  return worst;
}

const std::vector<std::string> kNames{"cam0", "cam1", "cam2", "cam3"};

// The case: a rig without hand-held views, whose COLMAP model pins the focal lengths
// poorly. The rig's own times add hundreds of points; focal lengths and centres come closer.
TEST(RigTimePoints, BringFocalLengthsAndCentresCloserToTheTruth) {
  const TruthRig truth = MakeRig();
  const ColmapModel model = MakeModel(truth, 25, 0.8, 520);
  const Rig without = RigFromColmap(model, kNames);
  RigOptions options;
  options.rig_times = {MakeTime(truth, 500, 0.3, 1), MakeTime(truth, 500, 0.3, 2)};
  const Rig with = RigFromColmap(model, kNames, options);
  ASSERT_TRUE(with.rig_time);
  const RigTimeReport& r = *with.rig_time;
  EXPECT_EQ(r.times_used, 2);
  EXPECT_GT(r.points_added, 600);
  EXPECT_GT(r.observations_added, 1800);
  EXPECT_LT(r.rms_after, 0.6);
  EXPECT_EQ(with.points.size(), without.points.size());  // point3d.ply stays COLMAP's
  const double f_without = FocalError(without), f_with = FocalError(with);
  const double c_without = CentreError(Centres(without), truth.centres);
  const double c_with = CentreError(Centres(with), truth.centres);
  fmt::print("focal error {:.3f}% -> {:.3f}%, centre error {:.3f}% -> {:.3f}%\n", 100 * f_without, 100 * f_with,
             100 * c_without, 100 * c_with);
  EXPECT_LT(f_with, 0.5 * f_without);
  EXPECT_LT(f_with, 0.003);
  EXPECT_LT(c_with, c_without);
}

// A time whose images match nothing (random descriptors: no match passes the ratio test) is
// skipped and named; the other time's points are still added and the rig still calibrates.
TEST(RigTimePoints, ATimeWithoutMatchesIsSkippedAndSaid) {
  const TruthRig truth = MakeRig();
  const ColmapModel model = MakeModel(truth, 25, 0.8, 520);
  RigTimeFeatures empty = MakeTime(truth, 300, 0.3, 9);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> d(0, 1);
  for (ViewFeatures& v : empty.views)
    for (int r = 0; r < v.descriptors.rows; ++r)
      for (int k = 0; k < 128; ++k) v.descriptors.at<float>(r, k) = d(rng);
  RigOptions options;
  options.rig_times = {MakeTime(truth, 300, 0.3, 1), empty};
  const Rig rig = RigFromColmap(model, kNames, options);
  ASSERT_TRUE(rig.rig_time);
  EXPECT_EQ(rig.rig_time->times, 2);
  EXPECT_EQ(rig.rig_time->times_used, 1);
  EXPECT_GT(rig.rig_time->points_added, 200);
  bool said = false;
  for (const std::string& note : rig.notes) said |= note.find("frame 9 skipped") != std::string::npos;
  EXPECT_TRUE(said);
}

// The static scene is seen again at every time: a second time of the same points extends the
// existing ones instead of adding them twice.
TEST(RigTimePoints, TheSameSceneAgainExtendsPointsInsteadOfRepeatingThem) {
  const TruthRig truth = MakeRig();
  BundleProblem problem;
  std::vector<int> rig_intrinsics;
  for (int c = 0; c < kCameras; ++c) {
    BundlePose pose;
    const Eigen::AngleAxisd aa(truth.cam_from_world[c].linear());
    pose.rotation = aa.angle() * aa.axis();
    pose.translation = truth.cam_from_world[c].translation();
    problem.poses.push_back(pose);
    problem.intrinsics.push_back({kF, kW / 2.0, kH / 2.0});
    rig_intrinsics.push_back(c);
  }
  const RigTimeFeatures once = MakeTime(truth, 300, 0.2, 4);
  const RigTimeReport first = AddRigTimePoints({once}, rig_intrinsics, &problem);
  const RigTimeReport again = AddRigTimePoints({once}, rig_intrinsics, &problem);
  EXPECT_GT(first.points_added, 200);
  EXPECT_LT(first.rms_before, 0.5);
  EXPECT_EQ(again.points_added, 0);
  EXPECT_GT(again.repeats, 2 * first.points_added);
}

TEST(RigTimePoints, SiftFindsFeaturesAndNamesAnUnreadableFile) {
  const auto dir = std::filesystem::temp_directory_path() / fmt::format("rig_time_sift_{}", ::getpid());
  std::filesystem::create_directories(dir);
  cv::Mat texture(240, 320, CV_8U);
  cv::randu(texture, 0, 255);
  cv::Mat blurred;
  cv::resize(texture(cv::Rect(0, 0, 80, 60)), blurred, texture.size(), 0, 0, cv::INTER_CUBIC);
  cv::imwrite((dir / "a.png").string(), blurred);
  const ViewFeatures f = ExtractSift(dir / "a.png");
  EXPECT_GT(f.pixels.size(), 50u);
  EXPECT_EQ(f.descriptors.rows, static_cast<int>(f.pixels.size()));
  try {
    ExtractSift(dir / "missing.png");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.png"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hdr4d
