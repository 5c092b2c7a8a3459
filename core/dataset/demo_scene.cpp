#include "core/dataset/demo_scene.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>

#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/util/parallel.h"
#include "core/geometry/ply.h"
#include "core/util/progress.h"
#include "core/files/staged_folder.h"

namespace hdr4d {
namespace fs = std::filesystem;
using Eigen::Vector3d;

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kBallRadius = 0.45;
constexpr double kEmitterRadius = 0.12;
// The bulb's visible radiance stays inside what the 0.125..32 s bracket captures (x = radiance
// x exposure <= 1 at 0.125 s), so a merge of the bracket can recover every pixel; the light it
// casts comes from a point source inside it.
const Vector3d kEmitterRadiance(6.0, 5.0, 3.6);
const Vector3d kLampIntensity(8.0, 6.5, 4.5);  // irradiance = I cos / (d^2 + kLampSoftening^2)
constexpr double kLampSoftening = 0.6;  // a lamp of finite size: no blow-up when the ball is close
const Vector3d kBallAlbedo(0.75, 0.25, 0.15);

// The ball rolls along x and bounces; the emitter circles at height 1.6.
Vector3d BallCenter(double t) {
  return {-1.0 + 2.0 * t, 0.3 * std::sin(2 * kPi * t),
          kBallRadius + 0.35 * std::abs(std::sin(3 * kPi * t))};
}

// Irradiance from the sun on a surface facing it; it dims to a fifth over the sequence.
Vector3d SunIrradiance(double t) { return Vector3d(9.4, 8.8, 7.9) * (1.0 - 0.8 * t); }
const Vector3d kAmbientIrradiance(0.02, 0.028, 0.04);  // faint sky fill: shadows stay above zero
const Vector3d kSunDirection = Vector3d(0.4, -0.3, 1.0).normalized();  // towards the sun

std::optional<double> HitSphere(const Vector3d& o, const Vector3d& d, const Vector3d& c, double r) {
  const Vector3d oc = o - c;
  const double b = oc.dot(d), cc = oc.squaredNorm() - r * r;
  const double disc = b * b - cc;
  if (disc < 0) return std::nullopt;
  const double s = std::sqrt(disc);
  if (-b - s > 1e-6) return -b - s;
  if (-b + s > 1e-6) return -b + s;
  return std::nullopt;
}

bool BallBlocks(const Vector3d& p, const Vector3d& dir, double max_dist, double t) {
  const auto hit = HitSphere(p, dir, BallCenter(t), kBallRadius);
  return hit && *hit < max_dist;
}

// Lambertian radiance albedo / pi x irradiance, with irradiance from the sun (directional),
// the lamp inside the bulb (inverse square) and an ambient fill.
Vector3d Shade(const Vector3d& p, const Vector3d& n, const Vector3d& albedo, double t) {
  Vector3d irradiance = kAmbientIrradiance;
  const double sun_cos = n.dot(kSunDirection);
  if (sun_cos > 0 && !BallBlocks(p + 1e-4 * n, kSunDirection, 1e9, t))
    irradiance += SunIrradiance(t) * sun_cos;
  const Vector3d to_emitter = DemoEmitterCenter(t) - p;
  const double dist = to_emitter.norm();
  const Vector3d l = to_emitter / dist;
  const double em_cos = n.dot(l);
  if (em_cos > 0 && !BallBlocks(p + 1e-4 * n, l, dist, t)) {
    irradiance += kLampIntensity * (em_cos / (dist * dist + kLampSoftening * kLampSoftening));
  }
  return albedo.cwiseProduct(irradiance) / kPi;
}

Vector3d Sky(const Vector3d& d, double t) {
  const double up = std::clamp(d.z(), 0.0, 1.0);
  return Vector3d(0.15, 0.2, 0.35) * (0.3 + 0.7 * up) * (1.0 - 0.6 * t);
}

}  // namespace

Vector3d DemoEmitterCenter(double t) {
  const double a = 2 * kPi * (0.15 + 0.8 * t);
  return {1.1 * std::cos(a), 1.1 * std::sin(a), 1.6};
}

Vector3d DemoSceneRadiance(const Vector3d& o, const Vector3d& d, double t) {
  double best = 1e30;
  int what = 0;  // 0 sky, 1 floor, 2 ball, 3 emitter
  if (d.z() < -1e-9) {
    const double s = -o.z() / d.z();
    if (s > 1e-6 && s < best) best = s, what = 1;
  }
  if (auto s = HitSphere(o, d, BallCenter(t), kBallRadius); s && *s < best) best = *s, what = 2;
  if (auto s = HitSphere(o, d, DemoEmitterCenter(t), kEmitterRadius); s && *s < best)
    best = *s, what = 3;
  const Vector3d p = o + best * d;
  switch (what) {
    case 1: {
      if (std::max(std::abs(p.x()), std::abs(p.y())) > 4.0) return Sky(d, t);  // finite floor
      const bool dark =
          (static_cast<int>(std::floor(p.x() * 2)) + static_cast<int>(std::floor(p.y() * 2))) & 1;
      const Vector3d albedo = dark ? Vector3d(0.04, 0.04, 0.05) : Vector3d(0.8, 0.78, 0.7);
      return Shade(p, Vector3d::UnitZ(), albedo, t);
    }
    case 2:
      return Shade(p, (p - BallCenter(t)).normalized(), kBallAlbedo, t);
    case 3:
      return kEmitterRadiance;
    default:
      return Sky(d, t);
  }
}

Image RenderDemoView(const Camera& camera, double t, int samples_per_axis) {
  const PinholeIntrinsics& k = camera.intrinsics;
  Image image(k.width, k.height, 3, Encoding::kLinear);
  const Eigen::Matrix4d world_from_cam = camera.WorldFromCamCv();
  const Vector3d origin = world_from_cam.block<3, 1>(0, 3);
  const Eigen::Matrix3d rotation = world_from_cam.block<3, 3>(0, 0);
  const int n = samples_per_axis;
  ParallelFor(k.height, 4, [&](std::int64_t y) {
    for (int x = 0; x < k.width; ++x) {
      Vector3d sum = Vector3d::Zero();
      for (int sy = 0; sy < n; ++sy) {
        for (int sx = 0; sx < n; ++sx) {
          // Stratified sample positions inside the pixel (corner-origin pixel coordinates).
          const double u = x + (sx + 0.5) / n, v = y + (sy + 0.5) / n;
          const Vector3d dir_cam((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
          sum += DemoSceneRadiance(origin, (rotation * dir_cam).normalized(), t);
        }
      }
      sum /= n * n;
      for (int c = 0; c < 3; ++c) image.at(x, static_cast<int>(y), c) = static_cast<float>(sum[c]);
    }
  });
  return image;
}

void DemoSceneOptions::Validate() const {
  if (width < 8 || height < 8 || width > 4096 || height > 4096)
    Fail("demo scene: size {}x{} must be within 8..4096", width, height);
  if (num_timestamps < 1) Fail("demo scene: need at least one timestamp, got {}", num_timestamps);
  if (rig == DemoRig::kMultiView && num_cameras < 2)
    Fail("demo scene: a multi-view rig needs at least 2 cameras (one is the test camera), got {}",
         num_cameras);
  if (exposures.empty()) Fail("demo scene: no exposures given");
  for (double e : exposures) {
    if (!(e > 0) || !std::isfinite(e))
      Fail("demo scene: exposure {} s must be positive and finite", e);
  }
  if (samples_per_axis < 1 || samples_per_axis > 16)
    Fail("demo scene: samples per axis {} must be within 1..16", samples_per_axis);
}

PointCloud DemoScenePointCloud(int count, std::uint64_t seed) {
  HDR4D_CHECK(count >= 10);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PointCloud cloud;
  // Colours in [0,1] for initialisation: radiance r shown as r / (1 + r).
  auto add = [&](const Vector3d& p, const Vector3d& radiance, double t) {
    cloud.positions.push_back(p.cast<float>());
    const Vector3d c = radiance.cwiseQuotient(radiance + Vector3d::Ones());
    cloud.colors.push_back(c.cast<float>());
    cloud.times.push_back(static_cast<float>(t));
  };
  const Vector3d above(0, 0, 6);
  // Half the points on the floor, a quarter on the sky dome (radius 9, seen from the ring of
  // cameras), the rest on the moving ball and bulb at random times.
  for (int i = 0; i < count / 2; ++i) {
    const Vector3d p(-4.0 + 8.0 * u(rng), -4.0 + 8.0 * u(rng), 0.0);
    const double t = u(rng);
    add(p, DemoSceneRadiance(above + Vector3d(p.x(), p.y(), 0), Vector3d(0, 0, -1), t), t);
  }
  for (int i = 0; i < count / 4; ++i) {
    const double a = 2 * kPi * u(rng), z = 0.1 + 0.9 * u(rng);
    const Vector3d d(std::sqrt(1 - z * z) * std::cos(a), std::sqrt(1 - z * z) * std::sin(a), z);
    const double t = u(rng);
    add(9.0 * d, Sky(d, t), t);
  }
  for (int i = static_cast<int>(cloud.size()); i < count; ++i) {
    const double t = u(rng);
    const double a = 2 * kPi * u(rng), z = 2 * u(rng) - 1;
    const Vector3d n(std::sqrt(1 - z * z) * std::cos(a), std::sqrt(1 - z * z) * std::sin(a), z);
    if (i % 5 == 0) {
      add(DemoEmitterCenter(t) + kEmitterRadius * n, kEmitterRadiance, t);
    } else {
      const Vector3d p = BallCenter(t) + kBallRadius * n;
      add(p, Shade(p, n, kBallAlbedo, t), t);
    }
  }
  return cloud;
}

namespace {

Vector3d RingPosition(double angle) { return {4.2 * std::cos(angle), 4.2 * std::sin(angle), 2.4}; }

// One HDR render per (view, timestamp); the LDR frames reference it once per exposure.
struct View {
  Split split;
  int camera_id;
  int time_index;
  Eigen::Matrix4d pose;
};

// Multi-view: a ring of cameras, the last held out for test. Monocular: the camera sweeps half a
// circle; every 4th frame is held out for test (the last one when there are fewer than 4).
std::vector<View> DemoViews(const DemoSceneOptions& options) {
  const int num_t = options.num_timestamps;
  const Vector3d target(0, 0, 0.5);
  std::vector<View> views;
  if (options.rig == DemoRig::kMultiView) {
    for (int c = 0; c < options.num_cameras; ++c) {
      const double angle = 2 * kPi * (c + 0.5) / options.num_cameras;
      const Split split = c == options.num_cameras - 1 ? Split::kTest : Split::kTrain;
      for (int i = 0; i < num_t; ++i)
        views.push_back(
            {split, c, i, LookAtWorldFromCamGl(RingPosition(angle), target, Vector3d::UnitZ())});
    }
  } else {
    for (int i = 0; i < num_t; ++i) {
      const double angle = kPi * (0.1 + 0.9 * i / std::max(1, num_t - 1));
      const bool test = num_t > 1 && (i % 4 == 3 || (num_t < 4 && i == num_t - 1));
      const Split split = test ? Split::kTest : Split::kTrain;
      views.push_back(
          {split, 0, i, LookAtWorldFromCamGl(RingPosition(angle), target, Vector3d::UnitZ())});
    }
  }
  return views;
}

// Renders one view's HDR image and adds its LDR frames to the dataset. Multi-view: every
// exposure at every view; monocular: exposures cycle across frames.
void AddViewFrames(const View& view,
                   const DemoSceneOptions& options,
                   const PinholeIntrinsics& intrinsics,
                   int frame_counter[3],
                   Dataset* dataset) {
  const fs::path& root = dataset->root;
  const int num_t = options.num_timestamps;
  const int num_e = static_cast<int>(options.exposures.size());
  const double t = num_t > 1 ? static_cast<double>(view.time_index) / (num_t - 1) : 0.0;
  const std::string stem = fmt::format("cam{:02d}_t{:03d}", view.camera_id, view.time_index);
  const std::string exr_rel = "hdr/" + stem + ".exr";
  Camera camera{intrinsics, view.pose};
  WriteImage(root / exr_rel, RenderDemoView(camera, t, options.samples_per_axis),
             {.format = PixelFormat::kFloat});
  std::vector<int> exposure_ids;
  if (options.rig == DemoRig::kMultiView) {
    for (int e = 0; e < num_e; ++e) exposure_ids.push_back(e);
  } else {
    exposure_ids.push_back(view.time_index % num_e);
  }
  for (int e : exposure_ids) {
    Frame frame;
    frame.split = view.split;
    frame.index = frame_counter[static_cast<int>(view.split)]++;
    frame.file_path = fmt::format("images/{}_e{}.png", stem, e);
    frame.image_path = root / frame.file_path;
    frame.exr_file_path = exr_rel;
    frame.hdr_path = root / exr_rel;
    frame.time_raw = frame.time = t;
    frame.exposure = options.exposures[e];
    frame.exposure_given = true;
    frame.camera_id = view.camera_id;
    frame.exposure_index = e;
    frame.camera = camera;
    (view.split == Split::kTrain ? dataset->train : dataset->test).push_back(frame);
  }
}

}  // namespace

Dataset MakeDemoScene(const DemoSceneOptions& options, const fs::path& final_root) {
  options.Validate();
  // Built beside its place and moved there when complete (core/files/staged_folder.h).
  StagedFolder staged(final_root);
  const fs::path& root = staged.path();
  constexpr double kFovX = 0.8;  // radians
  Dataset dataset;
  dataset.root = root;
  dataset.layout = "hdr4d";
  dataset.camera_angle_x = kFovX;
  const PinholeIntrinsics intrinsics =
      PinholeIntrinsics::FromFovX(kFovX, options.width, options.height);
  const std::vector<View> views = DemoViews(options);
  Progress progress("render demo scene", static_cast<std::int64_t>(views.size()));
  int frame_counter[3] = {0, 0, 0};
  for (const View& view : views) {
    AddViewFrames(view, options, intrinsics, frame_counter, &dataset);
    progress.Advance();
  }
  progress.Finish();
  dataset.time_max_raw = 1.0;
  // Initial points for training, as Blender-made scenes ship: surfaces sampled over time.
  WritePly(root / "point3d.ply", DemoScenePointCloud(6000, 1));
  dataset.point_cloud_path = root / "point3d.ply";
  WriteDataset(dataset, root);
  staged.Commit();
  RebaseDataset(&dataset, final_root);
  return dataset;
}

}  // namespace hdr4d
