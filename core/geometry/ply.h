// Point clouds in PLY: the initial points of a scene (point3d.ply) and exported clouds.
// Reads ascii and binary_little_endian files with vertex properties x, y, z (float or double),
// optional red/green/blue (integers scaled by the type's maximum, or floats taken as [0,1]) and
// an optional per-point `time` (HDR-4DGS honours it); every other property and element is
// skipped by its declared type. Writes binary_little_endian (or ascii) with x y z as float,
// red green blue as uchar and time as float when present.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <vector>

namespace hdr4d {

struct PointCloud {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> colors;  // in [0,1]; empty or one per position
  std::vector<float> times;             // empty or one per position

  std::size_t size() const { return positions.size(); }
  bool has_colors() const { return !colors.empty(); }
  bool has_times() const { return !times.empty(); }
};

// Throws hdr4d::Error naming the file for a missing file, a bad or unsupported header (big
// endian, list properties in the vertex element, a missing x/y/z), truncated data, an
// unparsable ascii number and non-finite coordinates, colours or times.
PointCloud ReadPly(const std::filesystem::path& path);
// The number of points (vertex element count) from the header alone, without reading the data:
// for a memory check before a huge cloud is read. Throws like ReadPly for a bad header.
std::int64_t ReadPlyVertexCount(const std::filesystem::path& path);

enum class PlyFormat { kBinaryLittleEndian, kAscii };

struct PlyWriteOptions {
  PlyFormat format = PlyFormat::kBinaryLittleEndian;
};

// Colours are clamped to [0,1] and rounded to 8 bits. Written through a temporary file and a
// rename. Throws hdr4d::Error when colors/times are neither empty nor one per point.
void WritePly(const std::filesystem::path& path,
              const PointCloud& cloud,
              const PlyWriteOptions& options = {});

}  // namespace hdr4d
