// The built-in demo scene: a small dynamic HDR scene rendered analytically (ray casting, no
// external assets), written as a dataset in the reference layout with linear EXR ground truth.
// It is the default input of the README's main command and a known-answer fixture for tests:
// a ball rolls across a checkered floor, a glowing bulb circles above it (a lamp that casts a
// moving shadow), and the sun dims over time, so the radiance spans more than 1e4:1 and the
// illumination changes with time. The brightest radiance stays within what the 0.125..32 s
// exposure bracket of HDR-4D-Syn captures, so merging the bracket can recover every pixel.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <vector>

#include "core/dataset/dataset.h"
#include "core/image/image.h"
#include "core/geometry/ply.h"

namespace hdr4d {

enum class DemoRig {
  kMultiView,  // fixed cameras, every exposure at every camera and timestamp
  kMonocular,  // one camera per timestamp moving around the scene, exposures cycling
};

struct DemoSceneOptions {
  int width = 96;
  int height = 96;
  int num_timestamps = 6;
  int num_cameras = 4;  // multi-view: cameras on a ring; the last one is the test camera
  DemoRig rig = DemoRig::kMultiView;
  std::vector<double> exposures = {0.125, 2.0, 32.0};  // seconds, as HDR-4D-Syn
  int samples_per_axis = 2;                            // supersampling per pixel (n x n)
  void Validate() const;
};

// Linear radiance seen along a ray at normalised time t in [0,1] (world axes: +Z up).
Eigen::Vector3d DemoSceneRadiance(const Eigen::Vector3d& origin,
                                  const Eigen::Vector3d& direction,
                                  double t);
// World position of the emitter's centre at time t (for tests of the camera convention).
Eigen::Vector3d DemoEmitterCenter(double t);

// Points on the scene's surfaces (floor, sky dome, ball and bulb at random times in [0,1], with
// a `time` each) and their colours r / (1 + r) of the radiance r: the point3d.ply that
// MakeDemoScene writes for initialisation.
PointCloud DemoScenePointCloud(int count, std::uint64_t seed);

// Renders one HDR view (Encoding::kLinear, RGB).
Image RenderDemoView(const Camera& camera, double t, int samples_per_axis);

// Renders every view to <root>/hdr/*.exr and writes transforms_{train,test}.json whose frames
// point at the LDR images <root>/images/*.png that `hdr4d synth-ldr` creates from the HDR, and
// <root>/point3d.ply (DemoScenePointCloud). The scene is built in a staging folder and moved to
// `root` when complete: `root` must be new or an empty folder (never merged into).
// Returns the dataset as written.
Dataset MakeDemoScene(const DemoSceneOptions& options, const std::filesystem::path& root);

}  // namespace hdr4d
