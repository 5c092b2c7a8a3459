#include "method/train/content_views.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace hdr4d::method {
namespace {

Camera LookingAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, double fov = 0.7) {
  Camera c;
  c.intrinsics = PinholeIntrinsics::FromFovX(fov, 200, 200);
  c.world_from_cam_gl = LookAtWorldFromCamGl(eye, target, Eigen::Vector3d::UnitZ());
  return c;
}

std::vector<Eigen::Vector3f> Ball(const Eigen::Vector3f& centre, float radius, int n,
                                  std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-radius, radius);
  std::vector<Eigen::Vector3f> p;
  while (int(p.size()) < n) {
    const Eigen::Vector3f d(u(rng), u(rng), u(rng));
    if (d.norm() <= radius) p.push_back(centre + d);
  }
  return p;
}

// A ring of cameras round an object sees all of it from every view: one view of content.
TEST(ContentViews, ARingRoundAnObjectHoldsOneView) {
  const auto points = Ball(Eigen::Vector3f::Zero(), 0.5f, 5000, 1);
  std::vector<Camera> ring;
  for (int k = 0; k < 12; ++k) {
    const double a = 2 * std::numbers::pi * k / 12;
    ring.push_back(LookingAt({4 * std::cos(a), 4 * std::sin(a), 1.0}, Eigen::Vector3d::Zero()));
  }
  const auto views = ContentViews(points, ring);
  ASSERT_TRUE(views.has_value());
  EXPECT_NEAR(*views, 1.0, 1e-9);
}

// A walk-around capture: four cameras, each facing one of four separate parts of the scene, so
// the content is four views' worth; with two cameras on each part, still four.
TEST(ContentViews, AWalkAroundCaptureHoldsOneViewPerPart) {
  std::vector<Eigen::Vector3f> points;
  std::vector<Camera> cameras;
  for (int part = 0; part < 4; ++part) {
    const double a = std::numbers::pi / 2 * part;
    const Eigen::Vector3d centre(10 * std::cos(a), 10 * std::sin(a), 0);
    const auto ball = Ball(centre.cast<float>(), 0.5f, 1000, 10 + part);
    points.insert(points.end(), ball.begin(), ball.end());
    // From 4 units inside the part, looking out at it: the others are behind or to the side.
    cameras.push_back(LookingAt(centre * 0.6, centre));
    cameras.push_back(LookingAt(centre * 0.6 + Eigen::Vector3d(0, 0, 1), centre));
  }
  const auto views = ContentViews(points, cameras);
  ASSERT_TRUE(views.has_value());
  EXPECT_NEAR(*views, 4.0, 1e-9);
}

// Points outside every view (behind the cameras, or beside them) do not count as content, and a
// cloud no camera sees, no cloud and no camera give no answer.
TEST(ContentViews, PointsNoCameraSeesAreNotContentAndNoneSeenIsNoAnswer) {
  auto points = Ball(Eigen::Vector3f::Zero(), 0.5f, 2000, 2);
  const std::vector<Camera> one{LookingAt({4, 0, 0}, Eigen::Vector3d::Zero())};
  const auto behind = Ball(Eigen::Vector3f(20, 0, 0), 1.0f, 2000, 3);
  points.insert(points.end(), behind.begin(), behind.end());
  const auto views = ContentViews(points, one);
  ASSERT_TRUE(views.has_value());
  EXPECT_NEAR(*views, 1.0, 1e-9);
  EXPECT_FALSE(ContentViews(behind, one).has_value());
  EXPECT_FALSE(ContentViews({}, one).has_value());
  EXPECT_FALSE(ContentViews(points, {}).has_value());
}

// A large cloud is subsampled by an even stride: the answer stays within 2% of every point's.
TEST(ContentViews, SubsamplingKeepsTheRatio) {
  // A wide floor: each camera of a ring sees about half of it.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f);
  std::vector<Eigen::Vector3f> floor;
  for (int i = 0; i < 100000; ++i) floor.emplace_back(u(rng), u(rng), 0.0f);
  std::vector<Camera> ring;
  for (int k = 0; k < 8; ++k) {
    const double a = 2 * std::numbers::pi * k / 8;
    ring.push_back(LookingAt({4 * std::cos(a), 4 * std::sin(a), 2.0}, Eigen::Vector3d::Zero()));
  }
  const auto all = ContentViews(floor, ring, 100000);
  const auto sampled = ContentViews(floor, ring);
  ASSERT_TRUE(all && sampled);
  EXPECT_GT(*all, 1.2);  // the ring's views see different parts of the floor
  EXPECT_NEAR(*sampled / *all, 1.0, 0.02);
}

}  // namespace
}  // namespace hdr4d::method
