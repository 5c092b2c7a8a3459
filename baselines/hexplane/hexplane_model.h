// The learned state of a HexPlane run: density and appearance planes, their bases, the
// appearance MLP, HDR-HexPlane's per-image exposure offsets, and the occupancy grid that skips
// empty space. Also the grid geometry the reference derives from the voxel count (resolution,
// ray-marching step and sample count) and its plane upsampling.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <vector>

#include "baselines/hexplane/app_mlp.h"
#include "baselines/hexplane/hex_field.h"
#include "baselines/hexplane/hexplane_config.h"

namespace hdr4d::baselines::hexplane {

// A 3D grid of occupied flags over the box (grid points at linspace(-1, 1, res), as the
// reference's emptiness volume). A point is kept when any corner of its cell is occupied: the
// reference's trilinear read of the 0/1 volume is > 0 exactly then.
struct OccupancyGrid {
  std::array<int, 3> res{0, 0, 0};
  std::vector<std::uint8_t> occupied;  // x fastest
  bool empty() const { return occupied.empty(); }
  bool Keeps(const float xyz[3]) const;
};

// The spatial resolution the reference gives a voxel count over a box (N_to_reso).
std::array<int, 3> ResolutionOf(std::int64_t voxels);
// The reference's upsampling targets: voxel counts and time grids after each upsampling
// (logarithmic steps from init to final, the first value dropped).
std::vector<std::int64_t> VoxelSchedule(const HexPlaneConfig& c);
std::vector<int> TimeGridSchedule(const HexPlaneConfig& c);

struct HexPlaneModel {
  HexPlaneConfig config;
  std::array<int, 3> grid{0, 0, 0};
  int time_grid = 0;
  HexPlanes<float> density, app;
  std::vector<float> density_basis;  // 3 x density_comps, ones at start
  std::vector<float> app_basis;      // app_dim x (3 app_comps), row-major
  std::vector<float> mlp;
  std::vector<float> exposure_offset;  // one per training image (log-HDR colours)
  std::vector<float> background;       // n x 3 coefficients of a learned background, or none
  OccupancyGrid occupancy;

  // Fresh parameters at the initial grid.
  static HexPlaneModel Create(const HexPlaneConfig& config, int num_train_images);
  AppMlpShape MlpShape() const;
  // World units between samples along a ray (mean cell size times step_ratio) and how many
  // samples span [near, far] (the reference: the box diagonal over the step, plus one).
  float StepSize() const;
  int NumSamples() const;
  // Bilinear resampling of every plane to the new resolution (the reference's upsampling).
  void Upsample(const std::array<int, 3>& new_grid, int new_time_grid);
  // Recomputes the occupancy grid (at the current resolution, points already empty stay so);
  // false (and the grid unchanged) when nothing would be occupied.
  bool UpdateOccupancy();
  // The offset of training image i, or the mean for any other view (i < 0).
  float OffsetOf(int image_index) const;

  void Save(const std::filesystem::path& file) const;
  static HexPlaneModel Load(const std::filesystem::path& file, const HexPlaneConfig& config);
  // The same bytes on a stream (a training checkpoint appends the trainer's state after them);
  // `file` names the source in errors.
  void Write(std::ostream& out) const;
  static HexPlaneModel Read(std::istream& in, const std::filesystem::path& file,
                            const HexPlaneConfig& config);
};

// Gradients with the model's shapes.
struct HexPlaneGrads {
  HexPlanes<float> density, app;
  std::vector<float> density_basis, app_basis, mlp, exposure_offset, background;
  explicit HexPlaneGrads(const HexPlaneModel& m);
  void SetZero();
  void Add(const HexPlaneGrads& other);
};

}  // namespace hdr4d::baselines::hexplane
