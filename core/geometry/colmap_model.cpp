#include "core/geometry/colmap_model.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/files/file_access.h"
#include "core/util/error.h"
#include "core/files/json_util.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

// COLMAP's model ids (src/base/camera_models.h) in id order, with their parameter counts.
struct ModelInfo {
  const char* name;
  int params;
};
constexpr ModelInfo kModels[] = {
    {"SIMPLE_PINHOLE", 3}, {"PINHOLE", 4},        {"SIMPLE_RADIAL", 4},
    {"RADIAL", 5},         {"OPENCV", 8},         {"OPENCV_FISHEYE", 8},
    {"FULL_OPENCV", 12},   {"FOV", 5},            {"SIMPLE_RADIAL_FISHEYE", 4},
    {"RADIAL_FISHEYE", 5}, {"THIN_PRISM_FISHEYE", 12}};
constexpr int kNumModels = sizeof(kModels) / sizeof(kModels[0]);

int ModelId(const std::string& name) {
  for (int i = 0; i < kNumModels; ++i)
    if (name == kModels[i].name) return i;
  return -1;
}

// A little-endian binary reader that names the file and what it was reading when data ends.
class BinaryReader {
 public:
  explicit BinaryReader(const fs::path& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) Fail("{}: cannot open", path.string());
  }
  template <typename T>
  T Read(const char* what) {
    T value;
    if (!in_.read(reinterpret_cast<char*>(&value), sizeof(T)))
      Fail("{}: truncated while reading {}", path_.string(), what);
    return value;
  }
  std::string ReadName() {
    std::string name;
    char c;
    while (in_.get(c) && c != '\0') name.push_back(c);
    if (!in_) Fail("{}: truncated while reading an image name", path_.string());
    return name;
  }
  // Counts come from the file: bound them so a corrupt count is an error, not a huge allocation.
  std::uint64_t ReadCount(const char* what, std::uint64_t limit) {
    const auto n = Read<std::uint64_t>(what);
    if (n > limit) Fail("{}: implausible {} count {}", path_.string(), what, n);
    return n;
  }

 private:
  fs::path path_;
  std::ifstream in_;
};

constexpr std::uint64_t kMaxCount = 1ull << 32;

template <typename T>
void Put(std::string& out, T value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

// Non-comment lines of a text model file, with their 1-based line numbers.
std::vector<std::pair<int, std::string>> TextLines(const fs::path& path) {
  RequireInputFile(path);  // a device or FIFO is refused before it is opened
  std::ifstream in(path);
  if (!in) Fail("{}: cannot open", path.string());
  std::vector<std::pair<int, std::string>> lines;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') {
      // images.txt: an image with no 2D points has an empty second line; keep it there.
      if (first == std::string::npos && path.filename() == "images.txt") lines.emplace_back(number, "");
      continue;
    }
    lines.emplace_back(number, line);
  }
  return lines;
}

template <typename T>
T Parse(std::istringstream& in, const fs::path& path, int line, const char* what) {
  T value;
  if (!(in >> value)) Fail("{}: line {}: cannot read {}", path.string(), line, what);
  return value;
}

void CheckCamera(const ColmapCamera& camera, const fs::path& path) {
  const int expected = ColmapModelParamCount(camera.model);
  if (expected < 0) Fail("{}: camera {}: unknown camera model '{}'", path.string(), camera.id, camera.model);
  if (static_cast<int>(camera.params.size()) != expected)
    Fail("{}: camera {}: model {} needs {} parameters, found {}", path.string(), camera.id,
         camera.model, expected, camera.params.size());
  if (camera.width <= 0 || camera.height <= 0)
    Fail("{}: camera {}: bad size {}x{}", path.string(), camera.id, camera.width, camera.height);
  for (std::size_t p = 0; p < camera.params.size(); ++p)
    if (!std::isfinite(camera.params[p]))
      Fail("{}: camera {}: parameter {} is {}", path.string(), camera.id, p, camera.params[p]);
}

// A pose COLMAP could have written: a finite rotation quaternion of non-zero length (it is
// normalised when used; a zero one became the identity rotation) and a finite translation.
// `where` is "line N" of a text model or "image ID" of a binary one.
void CheckImagePose(const ColmapImage& im, const fs::path& path, const std::string& where) {
  const Eigen::Vector4d q = im.cam_from_world_rotation.coeffs();
  if (!q.allFinite() || !(q.norm() > 1e-9))
    Fail("{}: {}: the rotation quaternion ({}, {}, {}, {}) is not a rotation", path.string(), where,
         im.cam_from_world_rotation.w(), q.x(), q.y(), q.z());
  if (!im.cam_from_world_translation.allFinite())
    Fail("{}: {}: the translation is not finite", path.string(), where);
}

ColmapModel ReadBinary(const fs::path& folder) {
  ColmapModel model;
  {
    const fs::path path = folder / "cameras.bin";
    BinaryReader r(path);
    const auto n = r.ReadCount("camera", kMaxCount);
    for (std::uint64_t i = 0; i < n; ++i) {
      ColmapCamera c;
      c.id = r.Read<std::int32_t>("camera id");
      const int model_id = r.Read<std::int32_t>("camera model");
      if (model_id < 0 || model_id >= kNumModels)
        Fail("{}: camera {}: unknown camera model id {}", path.string(), c.id, model_id);
      c.model = kModels[model_id].name;
      c.width = static_cast<int>(r.Read<std::uint64_t>("width"));
      c.height = static_cast<int>(r.Read<std::uint64_t>("height"));
      for (int p = 0; p < kModels[model_id].params; ++p) c.params.push_back(r.Read<double>("camera parameters"));
      CheckCamera(c, path);
      model.cameras[c.id] = c;
    }
  }
  {
    const fs::path path = folder / "images.bin";
    BinaryReader r(path);
    const auto n = r.ReadCount("image", kMaxCount);
    for (std::uint64_t i = 0; i < n; ++i) {
      ColmapImage im;
      im.id = r.Read<std::int32_t>("image id");
      double q[4], t[3];
      for (double& v : q) v = r.Read<double>("rotation");
      for (double& v : t) v = r.Read<double>("translation");
      im.cam_from_world_rotation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
      im.cam_from_world_translation = Eigen::Vector3d(t[0], t[1], t[2]);
      CheckImagePose(im, path, fmt::format("image {}", im.id));
      im.camera_id = r.Read<std::int32_t>("camera id");
      im.name = r.ReadName();
      const auto np = r.ReadCount("2D point", kMaxCount);
      im.points2d.reserve(np);
      im.point3d_ids.reserve(np);
      for (std::uint64_t p = 0; p < np; ++p) {
        const double x = r.Read<double>("2D point");
        const double y = r.Read<double>("2D point");
        im.points2d.emplace_back(x, y);
        im.point3d_ids.push_back(r.Read<std::int64_t>("3D point id"));
      }
      model.images[im.id] = std::move(im);
    }
  }
  {
    const fs::path path = folder / "points3D.bin";
    BinaryReader r(path);
    const auto n = r.ReadCount("3D point", kMaxCount);
    for (std::uint64_t i = 0; i < n; ++i) {
      ColmapPoint p;
      p.id = static_cast<std::int64_t>(r.Read<std::uint64_t>("3D point id"));
      for (int k = 0; k < 3; ++k) p.xyz[k] = r.Read<double>("3D point position");
      for (int k = 0; k < 3; ++k) p.rgb[k] = r.Read<std::uint8_t>("3D point colour") / 255.0f;
      p.error = r.Read<double>("3D point error");
      const auto nt = r.ReadCount("track", kMaxCount);
      for (std::uint64_t t = 0; t < nt; ++t) {
        const int image = r.Read<std::int32_t>("track image id");
        const int idx = r.Read<std::int32_t>("track point index");
        p.track.emplace_back(image, idx);
      }
      model.points[p.id] = std::move(p);
    }
  }
  return model;
}

ColmapModel ReadText(const fs::path& folder) {
  ColmapModel model;
  {
    const fs::path path = folder / "cameras.txt";
    for (const auto& [number, line] : TextLines(path)) {
      std::istringstream in(line);
      ColmapCamera c;
      c.id = Parse<int>(in, path, number, "camera id");
      c.model = Parse<std::string>(in, path, number, "camera model");
      c.width = Parse<int>(in, path, number, "width");
      c.height = Parse<int>(in, path, number, "height");
      double v;
      while (in >> v) c.params.push_back(v);
      CheckCamera(c, path);
      model.cameras[c.id] = c;
    }
  }
  {
    const fs::path path = folder / "images.txt";
    const auto lines = TextLines(path);
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const auto& [number, line] = lines[i];
      if (line.empty()) continue;  // a stray blank line between images
      std::istringstream in(line);
      ColmapImage im;
      im.id = Parse<int>(in, path, number, "image id");
      double q[4], t[3];
      for (double& v : q) v = Parse<double>(in, path, number, "rotation");
      for (double& v : t) v = Parse<double>(in, path, number, "translation");
      im.cam_from_world_rotation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
      im.cam_from_world_translation = Eigen::Vector3d(t[0], t[1], t[2]);
      CheckImagePose(im, path, fmt::format("line {}", number));
      im.camera_id = Parse<int>(in, path, number, "camera id");
      std::getline(in >> std::ws, im.name);
      if (im.name.empty()) Fail("{}: line {}: missing image name", path.string(), number);
      if (i + 1 < lines.size()) {
        const auto& [pnumber, pline] = lines[++i];
        std::istringstream pin(pline);
        double x, y;
        std::int64_t id;
        while (pin >> x >> y >> id) {
          im.points2d.emplace_back(x, y);
          im.point3d_ids.push_back(id);
        }
        if (!pin.eof()) Fail("{}: line {}: cannot read the 2D points", path.string(), pnumber);
      }
      model.images[im.id] = std::move(im);
    }
  }
  {
    const fs::path path = folder / "points3D.txt";
    for (const auto& [number, line] : TextLines(path)) {
      std::istringstream in(line);
      ColmapPoint p;
      p.id = Parse<std::int64_t>(in, path, number, "3D point id");
      for (int k = 0; k < 3; ++k) p.xyz[k] = Parse<double>(in, path, number, "position");
      for (int k = 0; k < 3; ++k) p.rgb[k] = Parse<int>(in, path, number, "colour") / 255.0f;
      p.error = Parse<double>(in, path, number, "error");
      int image, idx;
      while (in >> image >> idx) p.track.emplace_back(image, idx);
      if (!in.eof()) Fail("{}: line {}: cannot read the track", path.string(), number);
      model.points[p.id] = std::move(p);
    }
  }
  return model;
}

void CheckReferences(const ColmapModel& model, const fs::path& folder, const char* ext) {
  for (const auto& [id, image] : model.images)
    if (!model.cameras.count(image.camera_id))
      Fail("{}: image {} ({}) names camera {}, which is not in cameras{}",
           (folder / fmt::format("images{}", ext)).string(), id, image.name, image.camera_id, ext);
  for (const auto& [id, point] : model.points)
    for (const auto& [image, idx] : point.track) {
      const auto it = model.images.find(image);
      if (it == model.images.end())
        Fail("{}: point {} is seen by image {}, which is not in images{}",
             (folder / fmt::format("points3D{}", ext)).string(), id, image, ext);
      if (idx < 0 || idx >= static_cast<int>(it->second.points2d.size()))
        Fail("{}: point {}: image {} has no 2D point {}",
             (folder / fmt::format("points3D{}", ext)).string(), id, image, idx);
    }
}

}  // namespace

int ColmapModelParamCount(const std::string& model) {
  const int id = ModelId(model);
  return id < 0 ? -1 : kModels[id].params;
}

PinholeIntrinsics ColmapCamera::Pinhole() const {
  PinholeIntrinsics k;
  k.width = width;
  k.height = height;
  if (model == "SIMPLE_PINHOLE" || model == "SIMPLE_RADIAL" || model == "RADIAL") {
    k.fx = k.fy = params[0];
    k.cx = params[1];
    k.cy = params[2];
  } else if (model == "PINHOLE" || model == "OPENCV") {
    k.fx = params[0];
    k.fy = params[1];
    k.cx = params[2];
    k.cy = params[3];
  } else {
    Fail("COLMAP camera {}: model {} is not supported (use a pinhole, radial or OPENCV model)",
         id, model);
  }
  return k;
}

Eigen::Vector2d ColmapCamera::Radial(Eigen::Vector2d* tangential) const {
  if (tangential) tangential->setZero();
  if (model == "SIMPLE_RADIAL") return {params[3], 0};
  if (model == "RADIAL") return {params[3], params[4]};
  if (model == "OPENCV") {
    if (tangential) *tangential = {params[6], params[7]};
    return {params[4], params[5]};
  }
  return Eigen::Vector2d::Zero();
}

Eigen::Matrix4d ColmapImage::CamFromWorldCv() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = cam_from_world_rotation.normalized().toRotationMatrix();
  m.topRightCorner<3, 1>() = cam_from_world_translation;
  return m;
}

ColmapModel ReadColmapModel(const fs::path& folder) {
  std::error_code ec;
  const bool binary = fs::exists(folder / "cameras.bin", ec);
  const char* ext = binary ? ".bin" : ".txt";
  for (const char* name : {"cameras", "images", "points3D"}) {
    const fs::path path = folder / fmt::format("{}{}", name, ext);
    if (!fs::exists(path, ec))
      Fail("{}: file not found (a COLMAP sparse model has cameras, images and points3D, .bin or "
           ".txt)", path.string());
  }
  ColmapModel model = binary ? ReadBinary(folder) : ReadText(folder);
  CheckReferences(model, folder, ext);
  return model;
}

void WriteColmapModel(const fs::path& folder, const ColmapModel& model, ColmapFormat format) {
  std::string cameras, images, points;
  if (format == ColmapFormat::kBinary) {
    Put<std::uint64_t>(cameras, model.cameras.size());
    for (const auto& [id, c] : model.cameras) {
      const int model_id = ModelId(c.model);
      if (model_id < 0) Fail("camera {}: unknown camera model '{}'", id, c.model);
      Put<std::int32_t>(cameras, id);
      Put<std::int32_t>(cameras, model_id);
      Put<std::uint64_t>(cameras, c.width);
      Put<std::uint64_t>(cameras, c.height);
      for (double p : c.params) Put<double>(cameras, p);
    }
    Put<std::uint64_t>(images, model.images.size());
    for (const auto& [id, im] : model.images) {
      Put<std::int32_t>(images, id);
      const auto& q = im.cam_from_world_rotation;
      for (double v : {q.w(), q.x(), q.y(), q.z()}) Put<double>(images, v);
      for (int k = 0; k < 3; ++k) Put<double>(images, im.cam_from_world_translation[k]);
      Put<std::int32_t>(images, im.camera_id);
      images.append(im.name);
      images.push_back('\0');
      Put<std::uint64_t>(images, im.points2d.size());
      for (std::size_t p = 0; p < im.points2d.size(); ++p) {
        Put<double>(images, im.points2d[p].x());
        Put<double>(images, im.points2d[p].y());
        Put<std::int64_t>(images, im.point3d_ids[p]);
      }
    }
    Put<std::uint64_t>(points, model.points.size());
    for (const auto& [id, p] : model.points) {
      Put<std::uint64_t>(points, static_cast<std::uint64_t>(id));
      for (int k = 0; k < 3; ++k) Put<double>(points, p.xyz[k]);
      for (int k = 0; k < 3; ++k)
        Put<std::uint8_t>(points, static_cast<std::uint8_t>(std::clamp(p.rgb[k], 0.0f, 1.0f) * 255.0f + 0.5f));
      Put<double>(points, p.error);
      Put<std::uint64_t>(points, p.track.size());
      for (const auto& [image, idx] : p.track) {
        Put<std::int32_t>(points, image);
        Put<std::int32_t>(points, idx);
      }
    }
  } else {
    cameras = "# Camera list: CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n";
    for (const auto& [id, c] : model.cameras) {
      cameras += fmt::format("{} {} {} {}", id, c.model, c.width, c.height);
      for (double p : c.params) cameras += fmt::format(" {:.17g}", p);
      cameras += "\n";
    }
    images = "# IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n# POINTS2D[] as (X, Y, POINT3D_ID)\n";
    for (const auto& [id, im] : model.images) {
      const auto& q = im.cam_from_world_rotation;
      const auto& t = im.cam_from_world_translation;
      images += fmt::format("{} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {} {}\n", id,
                            q.w(), q.x(), q.y(), q.z(), t.x(), t.y(), t.z(), im.camera_id, im.name);
      for (std::size_t p = 0; p < im.points2d.size(); ++p)
        images += fmt::format("{}{:.17g} {:.17g} {}", p ? " " : "", im.points2d[p].x(),
                              im.points2d[p].y(), im.point3d_ids[p]);
      images += "\n";
    }
    points = "# POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n";
    for (const auto& [id, p] : model.points) {
      points += fmt::format("{} {:.17g} {:.17g} {:.17g}", id, p.xyz.x(), p.xyz.y(), p.xyz.z());
      for (int k = 0; k < 3; ++k)
        points += fmt::format(" {}", static_cast<int>(std::clamp(p.rgb[k], 0.0f, 1.0f) * 255.0f + 0.5f));
      points += fmt::format(" {:.17g}", p.error);
      for (const auto& [image, idx] : p.track) points += fmt::format(" {} {}", image, idx);
      points += "\n";
    }
  }
  const char* ext = format == ColmapFormat::kBinary ? ".bin" : ".txt";
  std::error_code ec;
  fs::create_directories(folder, ec);
  WriteTextFileAtomic(folder / fmt::format("cameras{}", ext), cameras);
  WriteTextFileAtomic(folder / fmt::format("images{}", ext), images);
  WriteTextFileAtomic(folder / fmt::format("points3D{}", ext), points);
}

fs::path FindColmapModelFolder(const fs::path& root) {
  std::error_code ec;
  for (const fs::path& candidate : {root, root / "sparse" / "0", root / "sparse"})
    if (fs::exists(candidate / "cameras.bin", ec) || fs::exists(candidate / "cameras.txt", ec))
      return candidate;
  Fail("{}: no COLMAP sparse model (cameras.bin or cameras.txt here, in sparse/0 or in sparse)",
       root.string());
}

}  // namespace hdr4d
