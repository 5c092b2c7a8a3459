#include "calibration/truth_comparison.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>

#include "calibration/rig_geometry.h"
#include "calibration/undistort.h"
#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/files/json_util.h"

namespace hdr4d {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int kFirstCode = 16, kLastCode = 240;

double Quantile(std::vector<double>* values, double q) {
  if (values->empty()) return 0;
  const std::size_t i = static_cast<std::size_t>(q * static_cast<double>(values->size() - 1));
  std::nth_element(values->begin(), values->begin() + static_cast<std::ptrdiff_t>(i), values->end());
  return (*values)[i];
}

// code -> (r, g, b) from a response CSV as calibrate writes it (# comments, a header).
std::vector<std::array<double, 3>> ReadResponseCsv(const fs::path& path) {
  std::ifstream in(path);
  if (!in) Fail("{}: cannot read the response", path.string());
  std::vector<std::array<double, 3>> table(256, {-1, -1, -1});
  std::string line;
  int line_number = 0, rows = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty() || line[0] == '#' || line.rfind("code", 0) == 0) continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream fields(line);
    int code = -1;
    std::array<double, 3> x{};
    if (!(fields >> code >> x[0] >> x[1] >> x[2]) || code < 0 || code > 255)
      Fail("{}: line {}: expected code,r,g,b with a code in 0..255", path.string(), line_number);
    table[code] = x;
    ++rows;
  }
  for (int z = kFirstCode; z <= kLastCode; ++z)
    if (table[z][0] < 0) Fail("{}: code {} is missing ({} rows)", path.string(), z, rows);
  return table;
}

Eigen::Matrix4d MatrixFromJson(const json& m, const fs::path& file, const std::string& camera) {
  Eigen::Matrix4d out;
  try {
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) out(r, c) = m.at(r).at(c).get<double>();
  } catch (const json::exception&) {
    Fail("{}: camera {}: transform_matrix is not a 4x4 array of numbers", file.string(), camera);
  }
  return out;
}

struct TruthCamera {
  std::string name;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double k1 = 0, k2 = 0;  // the capture's lens (RADIAL, normalised coordinates); 0: a pinhole
  double vignetting = 0;  // the capture's falloff v (radiance x 1 - v (r / r_corner)^2)
  int width = 0, height = 0;
  Eigen::Matrix4d world_from_cam_gl;
  std::array<double, 3> low{}, high{};
  std::map<int, std::string> hdr_files;  // frame -> file relative to truth/
};

std::vector<TruthCamera> ReadTruthCameras(const fs::path& truth) {
  const fs::path path = truth / "cameras.json";
  if (!fs::exists(path))
    Fail("{}: not found; --truth takes the truth/ folder of `hdr4d datagen --capture`",
         path.string());
  const json doc = ReadJsonFile(path);
  if (!doc.is_object() || doc.value("format", "") != "hdr4d-capture-truth")
    Fail("{}: not a capture truth file (format hdr4d-capture-truth)", path.string());
  std::vector<TruthCamera> cameras;
  try {
    for (const json& j : doc.at("cameras")) {
      TruthCamera c;
      c.name = j.at("name").get<std::string>();
      c.fx = j.at("fx").get<double>();
      c.fy = j.value("fy", c.fx);
      c.k1 = j.value("k1", 0.0);
      c.k2 = j.value("k2", 0.0);
      c.vignetting = j.value("vignetting", 0.0);
      c.cx = j.at("cx").get<double>();
      c.cy = j.at("cy").get<double>();
      c.width = j.at("width").get<int>();
      c.height = j.at("height").get<int>();
      c.world_from_cam_gl = MatrixFromJson(j.at("transform_matrix"), path, c.name);
      for (int ch = 0; ch < 3; ++ch) {
        c.low[ch] = j.at("measured_radiance").at("low").at(ch).get<double>();
        c.high[ch] = j.at("measured_radiance").at("high").at(ch).get<double>();
      }
      for (const auto& [frame, file] : j.at("hdr_files").items())
        c.hdr_files[std::stoi(frame)] = file.get<std::string>();
      cameras.push_back(std::move(c));
    }
  } catch (const json::exception& e) {
    Fail("{}: {}", path.string(), e.what());
  } catch (const std::invalid_argument&) {
    Fail("{}: hdr_files: a key is not a frame number", path.string());
  }
  if (cameras.empty()) Fail("{}: no cameras", path.string());
  return cameras;
}

const TruthCamera& FindTruth(const std::vector<TruthCamera>& cameras, const std::string& name,
                             const fs::path& where) {
  for (const TruthCamera& c : cameras)
    if (c.name == name) return c;
  Fail("{}: camera {} is not in the truth's cameras.json", where.string(), name);
}

// Rotation errors that the centres' errors cannot tilt: after the rotation fitted to the
// orientations, and between every pair of cameras (relative rotations need no alignment).
void CompareOrientations(const Rig& rig, const std::vector<const TruthCamera*>& matched, TruthComparison* out) {
  std::vector<Eigen::Matrix3d> from, to;
  for (std::size_t i = 0; i < rig.cameras.size(); ++i) {
    from.push_back(rig.cameras[i].world_from_cam_gl.topLeftCorner<3, 3>());
    to.push_back(matched[i]->world_from_cam_gl.topLeftCorner<3, 3>());
  }
  const Eigen::Matrix3d a = AlignOrientations(from, to);
  out->alignment_tilt_deg = RotationAngleDegrees(a, out->alignment.rotation);
  for (std::size_t i = 0; i < from.size(); ++i) {
    out->cameras[i].rotation_oriented_deg = RotationAngleDegrees(a * from[i], to[i]);
    out->max_rotation_oriented_deg = std::max(out->max_rotation_oriented_deg, out->cameras[i].rotation_oriented_deg);
    for (std::size_t j = i + 1; j < from.size(); ++j)
      out->max_relative_rotation_deg =
          std::max(out->max_relative_rotation_deg,
                   RotationAngleDegrees(from[i].transpose() * from[j], to[i].transpose() * to[j]));
  }
}

void CompareGeometry(const Rig& rig, const std::vector<TruthCamera>& truth, const fs::path& rig_file,
                     TruthComparison* out) {
  std::vector<Eigen::Vector3d> from, to;
  std::vector<const TruthCamera*> matched;
  for (const RigCamera& c : rig.cameras) {
    const TruthCamera& t = FindTruth(truth, c.name, rig_file);
    from.push_back(c.world_from_cam_gl.topRightCorner<3, 1>());
    to.push_back(t.world_from_cam_gl.topRightCorner<3, 1>());
    matched.push_back(&t);
  }
  if (from.size() < 3) {
    out->notes.push_back(fmt::format("geometry not compared: {} camera(s); a similarity needs 3",
                                     from.size()));
    return;
  }
  out->alignment = AlignSimilarity(from, to);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : to) centroid += p;
  centroid /= static_cast<double>(to.size());
  double sum = 0;
  for (const auto& p : to) sum += (p - centroid).squaredNorm();
  out->rig_size = std::sqrt(sum / static_cast<double>(to.size()));
  out->geometry = true;
  for (std::size_t i = 0; i < rig.cameras.size(); ++i) {
    const RigCamera& c = rig.cameras[i];
    const TruthCamera& t = *matched[i];
    CameraTruthError& e = out->cameras[i];
    e.geometry = true;
    const Eigen::Matrix3d aligned = out->alignment.rotation * c.world_from_cam_gl.topLeftCorner<3, 3>();
    e.rotation_deg = RotationAngleDegrees(aligned, t.world_from_cam_gl.topLeftCorner<3, 3>());
    e.position_error = (out->alignment.Apply(from[i]) - to[i]).norm();
    e.position_relative = out->rig_size > 0 ? e.position_error / out->rig_size : 0;
    e.focal = c.intrinsics.f;
    e.focal_truth = t.fx;
    e.focal_relative = std::abs(e.focal - t.fx) / t.fx;
    e.principal_point_px = std::hypot(c.intrinsics.cx - t.cx, c.intrinsics.cy - t.cy);
    out->max_rotation_deg = std::max(out->max_rotation_deg, e.rotation_deg);
    out->mean_rotation_deg += e.rotation_deg / static_cast<double>(rig.cameras.size());
    out->max_position_relative = std::max(out->max_position_relative, e.position_relative);
    out->mean_position_relative += e.position_relative / static_cast<double>(rig.cameras.size());
    out->max_focal_relative = std::max(out->max_focal_relative, e.focal_relative);
  }
  CompareOrientations(rig, matched, out);
}

void CompareResponse(const fs::path& calibrated, const fs::path& truth, TruthComparison* out) {
  const auto recovered = ReadResponseCsv(calibrated);
  const auto expected = ReadResponseCsv(truth);
  out->response = true;
  for (int ch = 0; ch < 3; ++ch) {
    double max = 0, sum = 0;
    int codes = 0;
    for (int z = kFirstCode; z <= kLastCode; ++z) {
      if (!(expected[z][ch] > 0)) continue;  // at or below a black pedestal: no exposure to compare
      const double rel = recovered[z][ch] / expected[z][ch] - 1;
      max = std::max(max, std::abs(rel));
      sum += rel * rel;
      ++codes;
    }
    out->response_max_relative[ch] = max;
    out->response_rms_relative[ch] = codes > 0 ? std::sqrt(sum / codes) : 0.0;
  }
}

struct HdrPair {
  std::size_t camera;  // index into out->cameras
  fs::path calibrated, truth;
  const TruthCamera* truth_camera;
  const RigCamera* rig_camera;  // null without rig.json
};

// The render as the calibrated camera delivers it: through the capture's true lens (each pixel's
// distorted ray undistorted, the render sampled bilinearly there, as datagen does) and then
// through calibrate's own undistortion with its calibrated intrinsics, when it resampled: the
// radiance the calibrated camera should deliver in its own geometry. Against it the HDR figures
// measure the radiometry alone (the geometry figures measure the rest); against the render
// itself, each bilinear resampling's blur of the texture and any residual distortion lower a
// pixel-by-pixel log-log slope too. Vignetting is not applied: calibrate divides out the falloff
// it measures (--vignetting), so the radiance it should deliver is the render's.
bool HasLens(const TruthCamera& t) { return t.k1 != 0 || t.k2 != 0; }

Image TruthAsCalibrated(const Image& render, const TruthCamera& t, const RigCamera* c) {
  Image out = render;
  if (HasLens(t)) {
    // OpenCV's pixel centres are at integers, ours at +0.5.
    const cv::Matx33d k(t.fx, 0, t.cx - 0.5, 0, t.fy > 0 ? t.fy : t.fx, t.cy - 0.5, 0, 0, 1);
    std::vector<cv::Point2f> pixels;
    pixels.reserve(render.num_pixels());
    for (int y = 0; y < render.height(); ++y)
      for (int x = 0; x < render.width(); ++x) pixels.emplace_back(static_cast<float>(x), static_cast<float>(y));
    std::vector<cv::Point2f> rays;
    cv::undistortPoints(pixels, rays, k, cv::Vec4d(t.k1, t.k2, 0, 0), cv::noArray(), k,
                        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 1e-6));
    // Bilinear in double (cv::remap rounds positions to 1/32 pixel, which shows on a texture).
    const int w = render.width(), h = render.height();
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const cv::Point2f& ray = rays[static_cast<std::size_t>(y) * w + x];
        const double u = std::clamp(static_cast<double>(ray.x), 0.0, w - 1.0);
        const double v = std::clamp(static_cast<double>(ray.y), 0.0, h - 1.0);
        const int x0 = std::min(static_cast<int>(u), w - 1), y0 = std::min(static_cast<int>(v), h - 1);
        const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
        const double fx = u - x0, fy = v - y0;
        for (int ch = 0; ch < render.channels(); ++ch)
          out.at(x, y, ch) = static_cast<float>(
              (1 - fy) * ((1 - fx) * render.at(x0, y0, ch) + fx * render.at(x1, y0, ch)) +
              fy * ((1 - fx) * render.at(x0, y1, ch) + fx * render.at(x1, y1, ch)));
      }
  }
  return c && c->undistort ? Undistort(out, c->intrinsics) : out;
}

// The log-log slope of calibrated against true radiance: per channel means removed, one least-
// squares fit over every measured value. `truth` is each pair's reference image.
double LogLogSlope(const std::vector<Image>& calibrated, const std::vector<Image>& truth,
                   const std::vector<std::vector<char>>& measured) {
  std::array<double, 3> mean_t{}, mean_c{};
  std::array<long, 3> n{};
  double sxy = 0, sxx = 0;
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t k = 0; k < calibrated.size(); ++k) {
      for (std::size_t i = 0; i < calibrated[k].num_pixels(); ++i) {
        if (!measured[k][i]) continue;
        for (int ch = 0; ch < 3; ++ch) {
          const double t = std::log(truth[k].data()[3 * i + ch]), c = std::log(calibrated[k].data()[3 * i + ch]);
          if (pass == 0) {
            mean_t[ch] += t;
            mean_c[ch] += c;
            ++n[ch];
          } else {
            sxy += (t - mean_t[ch]) * (c - mean_c[ch]);
            sxx += (t - mean_t[ch]) * (t - mean_t[ch]);
          }
        }
      }
    }
    for (int ch = 0; pass == 0 && ch < 3; ++ch) {
      mean_t[ch] /= std::max(n[ch], 1L);
      mean_c[ch] /= std::max(n[ch], 1L);
    }
  }
  return sxx > 0 ? sxy / sxx : 0.0;
}

// Each camera's own scale: the median over its values of scale x calibrated / truth per channel,
// and how far the cameras' scales spread from their median (what gains should have made agree).
void CompareCameraScales(const std::vector<HdrPair>& pairs, const std::vector<Image>& calibrated,
                         const std::vector<Image>& truth, const std::vector<std::vector<char>>& measured,
                         TruthComparison* out) {
  std::vector<std::array<std::vector<double>, 3>> ratio(out->cameras.size());
  for (std::size_t k = 0; k < pairs.size(); ++k)
    for (std::size_t i = 0; i < calibrated[k].num_pixels(); ++i)
      for (int ch = 0; measured[k][i] && ch < 3; ++ch)
        ratio[pairs[k].camera][ch].push_back(calibrated[k].data()[3 * i + ch] / truth[k].data()[3 * i + ch] *
                                             out->hdr_scale[ch]);
  double spread = 0;
  for (int ch = 0; ch < 3; ++ch) {
    std::vector<double> scales;
    for (std::size_t c = 0; c < ratio.size(); ++c)
      if (!ratio[c][ch].empty()) scales.push_back(out->cameras[c].hdr_scale[ch] = Quantile(&ratio[c][ch], 0.5));
    if (scales.size() < 2) continue;
    std::vector<double> sorted = scales;
    const double median = Quantile(&sorted, 0.5);
    for (double s : scales) spread = std::max(spread, std::abs(s / median - 1));
  }
  out->hdr_camera_disagreement = spread;
}

// A perfect geometric calibration's reference: the render through the true lens and its own
// undistortion, the resampling alone.
Image TruthAsPerfectlyCalibrated(const Image& render, const TruthCamera& t) {
  RigCamera exact;
  exact.intrinsics = {t.fx, t.cx, t.cy, t.k1, t.k2};
  exact.undistort = HasLens(t);
  return TruthAsCalibrated(render, t, &exact);
}

// Which pixels the brackets measure (every channel of the truth within the camera's measured
// radiance range, calibrated and rendered values positive); appends their truth / calibrated
// ratios per channel to `ratios`.
std::vector<char> MeasuredPixels(const Image& cal, const Image& tru, const Image& raw,
                                 const TruthCamera& camera, std::array<std::vector<double>, 3>* ratios) {
  std::vector<char> use(cal.num_pixels(), 0);
  for (std::size_t i = 0; i < cal.num_pixels(); ++i) {
    bool ok = true;
    for (int ch = 0; ch < 3; ++ch) {
      const double t = tru.data()[3 * i + ch], c = cal.data()[3 * i + ch];
      ok &= t >= camera.low[ch] && t <= camera.high[ch] && c > 0 && raw.data()[3 * i + ch] > 0;
    }
    use[i] = ok;
    if (!ok) continue;
    for (int ch = 0; ch < 3; ++ch)
      (*ratios)[ch].push_back(tru.data()[3 * i + ch] / static_cast<double>(cal.data()[3 * i + ch]));
  }
  return use;
}

void CompareHdr(const std::vector<HdrPair>& pairs, TruthComparison* out) {
  // Pass 1: the scale per channel, the median of truth / calibrated over measured pixels.
  std::array<std::vector<double>, 3> ratios;
  std::vector<Image> calibrated, truth, render, floor;  // truth: as calibrated (TruthAsCalibrated)
  std::vector<std::vector<char>> measured;
  long pixels = 0, excluded = 0;
  for (const HdrPair& p : pairs) {
    Image cal = ReadImage(p.calibrated).Rgb();
    Image raw = ReadImage(p.truth).Rgb();
    if (!cal.SameShape(raw))
      Fail("{}: {} pixels, the rendered {} has {}", p.calibrated.string(), cal.ShapeString(),
           p.truth.string(), raw.ShapeString());
    Image tru = TruthAsCalibrated(raw, *p.truth_camera, p.rig_camera);
    floor.push_back(TruthAsPerfectlyCalibrated(raw, *p.truth_camera));
    out->hdr_resampled_frames += HasLens(*p.truth_camera) || (p.rig_camera && p.rig_camera->undistort);
    std::vector<char> use = MeasuredPixels(cal, tru, raw, *p.truth_camera, &ratios);
    pixels += static_cast<long>(use.size());
    excluded += static_cast<long>(std::count(use.begin(), use.end(), 0));
    calibrated.push_back(std::move(cal));
    truth.push_back(std::move(tru));
    render.push_back(std::move(raw));
    measured.push_back(std::move(use));
  }
  if (ratios[0].empty()) {
    out->notes.push_back("HDR not compared: no pixel lies in the radiance range the brackets measure");
    return;
  }
  for (int ch = 0; ch < 3; ++ch) out->hdr_scale[ch] = Quantile(&ratios[ch], 0.5);
  // Pass 2: relative errors.
  std::vector<double> all;
  std::vector<std::pair<double, double>> by_radiance;  // (true luminance-free value, error)
  std::vector<std::vector<double>> per_camera(out->cameras.size());
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const Image &cal = calibrated[k], &tru = truth[k];
    for (std::size_t i = 0; i < cal.num_pixels(); ++i) {
      if (!measured[k][i]) continue;
      for (int ch = 0; ch < 3; ++ch) {
        const double t = tru.data()[3 * i + ch];
        const double rel = std::abs(out->hdr_scale[ch] * cal.data()[3 * i + ch] - t) / t;
        all.push_back(rel);
        by_radiance.emplace_back(t / out->hdr_scale[ch], rel);
        per_camera[pairs[k].camera].push_back(rel);
      }
    }
  }
  out->hdr = true;
  out->hdr_frames = static_cast<int>(pairs.size());
  out->hdr_values = static_cast<long>(all.size());
  out->hdr_excluded_fraction = pixels > 0 ? static_cast<double>(excluded) / pixels : 0;
  out->hdr_within_10_percent =
      static_cast<double>(std::count_if(all.begin(), all.end(), [](double r) { return r <= 0.1; })) /
      static_cast<double>(all.size());
  out->hdr_median_relative = Quantile(&all, 0.5);
  // The shadows: the darkest fifth of the measured values (in the calibrated scale of each
  // channel, so that a colour cast does not pick one channel).
  std::sort(by_radiance.begin(), by_radiance.end());
  std::vector<double> dark;
  for (std::size_t i = 0; i < by_radiance.size() / 5; ++i) dark.push_back(by_radiance[i].second);
  out->hdr_dark_median_relative = dark.empty() ? 0.0 : Quantile(&dark, 0.5);
  out->hdr_p90_relative = Quantile(&all, 0.9);
  for (std::size_t c = 0; c < per_camera.size(); ++c) {
    if (per_camera[c].empty()) continue;
    out->cameras[c].hdr = true;
    out->cameras[c].hdr_values = static_cast<long>(per_camera[c].size());
    out->cameras[c].hdr_median_relative = Quantile(&per_camera[c], 0.5);
  }
  out->hdr_loglog_slope = LogLogSlope(calibrated, truth, measured);
  out->hdr_loglog_slope_render = LogLogSlope(calibrated, render, measured);
  out->hdr_loglog_slope_render_floor = LogLogSlope(floor, render, measured);
  CompareCameraScales(pairs, calibrated, truth, measured, out);
}

}  // namespace

Similarity AlignSimilarity(const std::vector<Eigen::Vector3d>& from,
                           const std::vector<Eigen::Vector3d>& to) {
  if (from.size() != to.size())
    Fail("similarity alignment: {} points against {}", from.size(), to.size());
  if (from.size() < 3) Fail("similarity alignment: {} points; it needs at least 3", from.size());
  const Eigen::Index n = static_cast<Eigen::Index>(from.size());
  Eigen::Matrix3Xd a(3, n), b(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    a.col(i) = from[i];
    b.col(i) = to[i];
  }
  // Collinear (or coincident) points leave the rotation about their line free.
  for (const Eigen::Matrix3Xd* m : {&a, &b}) {
    const Eigen::Matrix3Xd centred = m->colwise() - m->rowwise().mean();
    const Eigen::JacobiSVD<Eigen::Matrix3Xd> svd(centred);
    const Eigen::Vector3d s = svd.singularValues();
    if (!(s(0) > 0) || s(1) < 1e-6 * s(0))
      Fail("similarity alignment: the {} points lie on a line; the rotation is not determined",
           n);
  }
  const Eigen::Matrix4d t = Eigen::umeyama(a, b, true);
  Similarity out;
  const Eigen::Matrix3d sr = t.topLeftCorner<3, 3>();
  out.scale = std::cbrt(sr.determinant());
  out.rotation = sr / out.scale;
  out.translation = t.topRightCorner<3, 1>();
  return out;
}

Eigen::Matrix3d AlignOrientations(const std::vector<Eigen::Matrix3d>& from,
                                  const std::vector<Eigen::Matrix3d>& to) {
  if (from.size() != to.size() || from.empty())
    Fail("orientation alignment: {} rotations against {}", from.size(), to.size());
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < from.size(); ++i) sum += to[i] * from[i].transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

double RotationAngleDegrees(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  // The nearest rotation to a^T b first: the truth's matrices come from Blender in float32, off
  // orthonormal by ~6e-8, enough to move (trace - 1) / 2 by ~1e-7: acos then reads angles of
  // 0.01 deg wrong by half and clamps those under ~0.03 deg to exactly 0 (issue 54's 0.000 deg
  // row). Then atan2 of the axis part against the trace part, which keeps small angles where
  // acos of a cosine near 1 does not.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(a.transpose() * b, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  const Eigen::Matrix3d r = svd.matrixU() * d * svd.matrixV().transpose();
  const Eigen::Vector3d axis(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));
  return std::atan2(axis.norm(), r.trace() - 1) * 180.0 / M_PI;
}

TruthComparison CompareWithTruth(const fs::path& calibrated, const fs::path& truth) {
  const std::vector<TruthCamera> truth_cameras = ReadTruthCameras(truth);
  TruthComparison out;
  for (const TruthCamera& t : truth_cameras) out.cameras.push_back({.name = t.name});

  const fs::path rig_file = calibrated / "rig.json";
  std::optional<Rig> read_rig;
  if (fs::exists(rig_file)) {
    const Rig& rig = read_rig.emplace(ReadRigJson(rig_file));
    // Results in the rig's camera order, which is the capture's (sorted names).
    std::vector<CameraTruthError> ordered;
    for (const RigCamera& c : rig.cameras) {
      FindTruth(truth_cameras, c.name, rig_file);
      ordered.push_back({.name = c.name});
    }
    for (const TruthCamera& t : truth_cameras)
      if (!rig.Find(t.name)) {
        ordered.push_back({.name = t.name});
        out.notes.push_back(fmt::format("camera {} is not in {}", t.name, rig_file.string()));
      }
    out.cameras = std::move(ordered);
    CompareGeometry(rig, truth_cameras, rig_file, &out);
  } else {
    out.notes.push_back(fmt::format("geometry not compared: no {}", rig_file.string()));
  }

  if (fs::exists(calibrated / "response.csv")) {
    CompareResponse(calibrated / "response.csv", truth / "response.csv", &out);
  } else {
    out.notes.push_back("response not compared: no response.csv (geometry stage only?)");
  }

  std::vector<HdrPair> pairs;
  for (std::size_t c = 0; c < out.cameras.size(); ++c) {
    const TruthCamera& t = FindTruth(truth_cameras, out.cameras[c].name, truth / "cameras.json");
    out.cameras[c].vignetting_truth = t.vignetting;
    const fs::path folder = calibrated / "hdr" / t.name;
    if (!fs::is_directory(folder)) continue;
    for (const auto& entry : fs::directory_iterator(folder)) {
      if (entry.path().extension() != ".exr") continue;
      int frame = -1;
      try {
        frame = std::stoi(entry.path().stem().string());
      } catch (const std::exception&) {
        Fail("{}: not a frame number", entry.path().string());
      }
      const auto it = t.hdr_files.find(frame);
      if (it == t.hdr_files.end())
        Fail("{}: camera {} has no frame {} in the truth", entry.path().string(), t.name, frame);
      pairs.push_back({c, entry.path(), truth / it->second, &t, read_rig ? read_rig->Find(t.name) : nullptr});
    }
  }
  std::sort(pairs.begin(), pairs.end(),
            [](const HdrPair& a, const HdrPair& b) { return a.calibrated < b.calibrated; });
  if (pairs.empty()) {
    out.notes.push_back(fmt::format("HDR not compared: no {}", (calibrated / "hdr").string()));
  } else {
    CompareHdr(pairs, &out);
  }
  return out;
}

json TruthComparisonJson(const TruthComparison& c) {
  json cameras = json::array();
  for (const CameraTruthError& e : c.cameras) {
    json j = {{"name", e.name}};
    if (e.geometry) {
      j["rotation_error_deg"] = e.rotation_deg;
      j["rotation_error_oriented_deg"] = e.rotation_oriented_deg;
      j["position_error"] = e.position_error;
      j["position_error_relative"] = e.position_relative;
      j["focal"] = e.focal;
      j["focal_truth"] = e.focal_truth;
      j["focal_error_relative"] = e.focal_relative;
      j["principal_point_error_px"] = e.principal_point_px;
    }
    j["vignetting_truth"] = e.vignetting_truth;
    if (e.hdr) {
      j["hdr_median_relative_error"] = e.hdr_median_relative;
      j["hdr_scale_against_truth"] = e.hdr_scale;
      j["hdr_values"] = e.hdr_values;
    }
    cameras.push_back(j);
  }
  json out = {{"cameras", cameras}, {"notes", c.notes}};
  if (c.geometry) {
    out["geometry"] = {{"rig_size", c.rig_size},
                       {"rig_size_definition", "RMS distance of the true camera centres from their centroid"},
                       {"similarity_scale", c.alignment.scale},
                       {"max_rotation_error_deg", c.max_rotation_deg},
                       {"mean_rotation_error_deg", c.mean_rotation_deg},
                       {"max_rotation_error_oriented_deg", c.max_rotation_oriented_deg},
                       {"max_relative_rotation_error_deg", c.max_relative_rotation_deg},
                       {"alignment_tilt_deg", c.alignment_tilt_deg},
                       {"rotation_error_definitions",
                        "rotation_error: after the similarity fitted to the centres (their errors tilt it); "
                        "oriented: after the rotation fitted to the orientations; relative: max over camera "
                        "pairs of the error of R_i^T R_j (no alignment); alignment_tilt: angle between the two "
                        "alignments"},
                       {"max_position_error_relative", c.max_position_relative},
                       {"mean_position_error_relative", c.mean_position_relative},
                       {"max_focal_error_relative", c.max_focal_relative}};
  }
  if (c.response) {
    out["response"] = {{"codes", {kFirstCode, kLastCode}},
                       {"max_relative_error", c.response_max_relative},
                       {"rms_relative_error", c.response_rms_relative}};
  }
  if (c.hdr) {
    out["hdr"] = {{"frames", c.hdr_frames},
                  {"values", c.hdr_values},
                  {"scale", c.hdr_scale},
                  {"median_relative_error", c.hdr_median_relative},
                  {"p90_relative_error", c.hdr_p90_relative},
                  {"within_10_percent", c.hdr_within_10_percent},
                  {"loglog_slope", c.hdr_loglog_slope},
                  {"loglog_slope_render", c.hdr_loglog_slope_render},
                  {"loglog_slope_render_floor", c.hdr_loglog_slope_render_floor},
                  {"resampled_frames", c.hdr_resampled_frames},
                  {"reference",
                   "the rendered EXR through the capture's true lens and then calibrate's own "
                   "undistortion (resampled_frames of them; the others as rendered); "
                   "loglog_slope_render is the slope against the render itself, "
                   "loglog_slope_render_floor that of a perfect calibration (the true lens undistorted "
                   "with itself: the resampling's blur alone)"},
                  {"dark_fifth_median_relative_error", c.hdr_dark_median_relative},
                  {"camera_disagreement", c.hdr_camera_disagreement},
                  {"camera_disagreement_definition",
                   "max over cameras and channels of |camera scale / median camera scale - 1|, a "
                   "camera's scale the median of calibrated / true radiance over its values"},
                  {"excluded_pixel_fraction", c.hdr_excluded_fraction}};
  }
  return out;
}

std::string TruthComparisonMarkdown(const TruthComparison& c) {
  std::string md = "| camera | rotation error (deg) | position error (% of rig size) | focal / truth (px) | "
                   "focal error | principal point error (px) | HDR median rel. error |\n"
                   "|---|---|---|---|---|---|---|\n";
  for (const CameraTruthError& e : c.cameras) {
    md += fmt::format("| {} | {} | {} | {} | {} | {} | {} |\n", e.name,
                      e.geometry ? fmt::format("{:.3f}", e.rotation_deg) : "-",
                      e.geometry ? fmt::format("{:.2f}", 100 * e.position_relative) : "-",
                      e.geometry ? fmt::format("{:.1f} / {:.1f}", e.focal, e.focal_truth) : "-",
                      e.geometry ? fmt::format("{:.2f}%", 100 * e.focal_relative) : "-",
                      e.geometry ? fmt::format("{:.2f}", e.principal_point_px) : "-",
                      e.hdr ? fmt::format("{:.1f}%", 100 * e.hdr_median_relative) : "-");
  }
  md += "\n";
  if (c.geometry) {
    md += fmt::format(
        "- geometry (after a similarity, scale {:.4g}): rotation error max {:.3f} deg, mean {:.3f} "
        "deg; position error max {:.2f}%, mean {:.2f}% of the rig size ({:.3g} units, the RMS "
        "distance of the true centres from their centroid); focal error max {:.2f}%; rotation error "
        "max {:.3f} deg after the rotation fitted to the orientations, {:.3f} deg between camera pairs "
        "(relative rotations), the centres' similarity tilted {:.3f} deg from the orientations'\n",
        c.alignment.scale, c.max_rotation_deg, c.mean_rotation_deg, 100 * c.max_position_relative,
        100 * c.mean_position_relative, c.rig_size, 100 * c.max_focal_relative, c.max_rotation_oriented_deg,
        c.max_relative_rotation_deg, c.alignment_tilt_deg);
  }
  if (c.response) {
    md += fmt::format(
        "- response (codes {}-{}, x(128) = 1): max relative error r {:.1f}%, g {:.1f}%, b {:.1f}%; "
        "RMS r {:.1f}%, g {:.1f}%, b {:.1f}%\n",
        kFirstCode, kLastCode, 100 * c.response_max_relative[0], 100 * c.response_max_relative[1],
        100 * c.response_max_relative[2], 100 * c.response_rms_relative[0],
        100 * c.response_rms_relative[1], 100 * c.response_rms_relative[2]);
  }
  if (c.hdr) {
    md += fmt::format(
        "- fused HDR vs rendered EXR ({} frames, {} values, one scale per channel {:.4g} {:.4g} "
        "{:.4g}): median relative error {:.1f}%, 90th percentile {:.1f}%, {:.1f}% of values "
        "within 10%; {:.1f}% of pixels excluded (outside the radiance the brackets measure); "
        "log-log slope {:.3f} ({:.3f} against the render itself, where a perfect calibration reads {:.3f}; "
        "{} frames' reference resampled through the true lens and calibrate's undistortion); the darkest fifth {:.1f}% (median); the cameras' "
        "scales against the truth {:.1f}% apart at most\n",
        c.hdr_frames, c.hdr_values, c.hdr_scale[0], c.hdr_scale[1], c.hdr_scale[2],
        100 * c.hdr_median_relative, 100 * c.hdr_p90_relative, 100 * c.hdr_within_10_percent,
        100 * c.hdr_excluded_fraction, c.hdr_loglog_slope, c.hdr_loglog_slope_render, c.hdr_loglog_slope_render_floor,
        c.hdr_resampled_frames,
        100 * c.hdr_dark_median_relative,
        100 * c.hdr_camera_disagreement);
  }
  for (const std::string& note : c.notes) md += "- " + note + "\n";
  return md;
}

}  // namespace hdr4d
