// checkpoint.bin of a HexPlane run: a magic tag, the grid, then every array with its length
// (binary_io.h); a training checkpoint appends the trainer's state (hexplane_train_state.h).
#include <cstring>
#include <fstream>

#include "baselines/hexplane/binary_io.h"
#include "baselines/hexplane/hexplane_model.h"
#include "core/files/atomic_file.h"
#include "core/util/error.h"

namespace hdr4d::baselines::hexplane {
namespace {

constexpr char kMagic[8] = {'H', 'E', 'X', 'P', 'L', 'N', '0', '1'};

}  // namespace

void HexPlaneModel::Save(const std::filesystem::path& file) const {
  WriteFileAtomic(file, [&](std::ostream& out) { Write(out); });
}

void HexPlaneModel::Write(std::ostream& out) const {
  out.write(kMagic, sizeof kMagic);
  const std::int32_t header[5] = {grid[0], grid[1], grid[2], time_grid,
                                  std::int32_t(exposure_offset.size())};
  out.write(reinterpret_cast<const char*>(header), sizeof header);
  for (const HexPlanes<float>* planes : {&density, &app})
    for (const Plane<float>* p : planes->All()) WriteArray(out, p->data);
  WriteArray(out, density_basis);
  WriteArray(out, app_basis);
  WriteArray(out, mlp);
  WriteArray(out, exposure_offset);
  const std::int32_t occ[3] = {occupancy.res[0], occupancy.res[1], occupancy.res[2]};
  out.write(reinterpret_cast<const char*>(occ), sizeof occ);
  WriteArray(out, occupancy.occupied);
  // Only a learned background (the configuration says which): older checkpoints read as before.
  if (!background.empty()) WriteArray(out, background);
}

HexPlaneModel HexPlaneModel::Load(const std::filesystem::path& file, const HexPlaneConfig& config) {
  std::ifstream in(file, std::ios::binary);
  if (!in) Fail("{}: cannot open the HexPlane checkpoint", file.string());
  return Read(in, file, config);
}

HexPlaneModel HexPlaneModel::Read(std::istream& in, const std::filesystem::path& file,
                                  const HexPlaneConfig& config) {
  char magic[8];
  in.read(magic, sizeof magic);
  if (!in || std::memcmp(magic, kMagic, sizeof kMagic) != 0)
    Fail("{}: not a HexPlane checkpoint (bad magic)", file.string());
  std::int32_t h[5];
  in.read(reinterpret_cast<char*>(h), sizeof h);
  if (!in || h[0] < 2 || h[1] < 2 || h[2] < 2 || h[3] < 2 || h[4] < 0 || h[0] > 65536 ||
      h[1] > 65536 || h[2] > 65536 || h[3] > 65536)
    Fail("{}: bad HexPlane grid header", file.string());
  HexPlaneModel m = Create(config, h[4]);
  m.Upsample({h[0], h[1], h[2]}, h[3]);  // shapes only: every value is read below
  const std::string name = file.string();  // for errors
  for (HexPlanes<float>* planes : {&m.density, &m.app})
    for (Plane<float>* p : planes->All()) ReadArray(in, p->data.size(), name, "a plane", &p->data);
  ReadArray(in, m.density_basis.size(), name, "the density basis", &m.density_basis);
  ReadArray(in, m.app_basis.size(), name, "the appearance basis", &m.app_basis);
  ReadArray(in, m.mlp.size(), name, "the appearance MLP", &m.mlp);
  ReadArray(in, m.exposure_offset.size(), name, "the exposure offsets", &m.exposure_offset);
  std::int32_t occ[3];
  in.read(reinterpret_cast<char*>(occ), sizeof occ);
  if (!in || occ[0] < 0 || occ[1] < 0 || occ[2] < 0 || occ[0] > 4096 || occ[1] > 4096 ||
      occ[2] > 4096)
    Fail("{}: bad occupancy header", name);
  m.occupancy.res = {occ[0], occ[1], occ[2]};
  const std::size_t cells = std::size_t(occ[0]) * occ[1] * occ[2];
  ReadArray(in, cells, name, "the occupancy grid", &m.occupancy.occupied);
  if (cells > 0 && (occ[0] < 2 || occ[1] < 2 || occ[2] < 2))
    Fail("{}: occupancy grid under 2 cells along an axis", name);
  if (!m.background.empty())
    ReadArray(in, m.background.size(), name, "the learned background", &m.background);
  return m;
}

}  // namespace hdr4d::baselines::hexplane
