#include "calibration/rig_time_points.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <unordered_map>

#include "core/util/error.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

// A rig camera as the matching sees it: pose, intrinsics and its undistorted pixels.
struct View {
  BundlePose pose;
  Eigen::Matrix3d r;
  Eigen::Vector3d t, centre;
  BundleIntrinsics k;
  const ViewFeatures* features = nullptr;
  std::vector<Eigen::Vector2d> normalised;
};

// The fundamental matrix between the undistorted pixels (f x + c) of views a and b.
Eigen::Matrix3d Fundamental(const View& a, const View& b) {
  const Eigen::Matrix3d r = b.r * a.r.transpose();
  const Eigen::Vector3d t = b.t - r * a.t;
  Eigen::Matrix3d skew;
  skew << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
  auto k_inverse = [](const BundleIntrinsics& k) {
    Eigen::Matrix3d m;
    m << 1 / k.f, 0, -k.cx / k.f, 0, 1 / k.f, -k.cy / k.f, 0, 0, 1;
    return m;
  };
  return k_inverse(b.k).transpose() * skew * r * k_inverse(a.k);
}

// Sampson's first-order distance (px) of the undistorted pixels ua, ub from F's epipolar geometry.
double SampsonPixels(const Eigen::Matrix3d& f, const Eigen::Vector3d& ua, const Eigen::Vector3d& ub) {
  const Eigen::Vector3d fa = f * ua, fb = f.transpose() * ub;
  const double denominator = fa.head<2>().squaredNorm() + fb.head<2>().squaredNorm();
  return denominator > 0 ? std::abs(ub.dot(fa)) / std::sqrt(denominator) : 0.0;
}

Eigen::Vector3d Undistorted(const View& v, int i) {
  return {v.k.f * v.normalised[i].x() + v.k.cx, v.k.f * v.normalised[i].y() + v.k.cy, 1.0};
}

// Matches that pass the ratio test both ways and are each other's best (a, b row indices).
std::vector<std::pair<int, int>> MutualMatches(const cv::Mat& a, const cv::Mat& b, double ratio) {
  std::vector<std::pair<int, int>> matches;
  if (a.rows < 2 || b.rows < 2) return matches;
  cv::BFMatcher matcher(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> ab, ba;
  matcher.knnMatch(a, b, ab, 2);
  matcher.knnMatch(b, a, ba, 2);
  auto passes = [ratio](const std::vector<cv::DMatch>& m) {
    return m.size() == 2 && m[0].distance < ratio * m[1].distance;
  };
  for (std::size_t i = 0; i < ab.size(); ++i) {
    if (!passes(ab[i])) continue;
    const int j = ab[i][0].trainIdx;
    if (passes(ba[j]) && ba[j][0].trainIdx == static_cast<int>(i)) matches.emplace_back(static_cast<int>(i), j);
  }
  return matches;
}

struct TrackObservation {
  int camera = 0, keypoint = 0;
};
using Track = std::vector<TrackObservation>;

int Root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// Matches of every camera pair of one time under the Sampson bound, joined into tracks with at
// most one keypoint per camera (a track that joins two keypoints of one camera is inconsistent).
std::vector<Track> TracksOfTime(const std::vector<View>& views, const RigTimeOptions& options, RigTimeReport* report) {
  std::vector<int> offset(views.size() + 1, 0);
  for (std::size_t c = 0; c < views.size(); ++c) offset[c + 1] = offset[c] + static_cast<int>(views[c].normalised.size());
  std::vector<int> parent(offset.back());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = static_cast<int>(i);
  std::vector<bool> matched(parent.size(), false);
  for (std::size_t a = 0; a < views.size(); ++a)
    for (std::size_t b = a + 1; b < views.size(); ++b) {
      const auto matches = MutualMatches(views[a].features->descriptors, views[b].features->descriptors, options.ratio);
      report->matches += static_cast<int>(matches.size());
      if (matches.empty()) continue;
      const Eigen::Matrix3d f = Fundamental(views[a], views[b]);
      for (const auto& [i, j] : matches) {
        if (!(SampsonPixels(f, Undistorted(views[a], i), Undistorted(views[b], j)) < options.max_sampson_pixels)) continue;
        ++report->matches_kept;
        const int na = offset[a] + i, nb = offset[b] + j;
        matched[na] = matched[nb] = true;
        parent[Root(parent, na)] = Root(parent, nb);
      }
    }
  std::map<int, Track> by_root;
  for (std::size_t c = 0; c < views.size(); ++c)
    for (int i = 0; i < static_cast<int>(views[c].normalised.size()); ++i)
      if (matched[offset[c] + i]) by_root[Root(parent, offset[c] + i)].push_back({static_cast<int>(c), i});
  std::vector<Track> tracks;
  for (auto& [root, track] : by_root) {
    std::vector<int> cameras;
    for (const TrackObservation& o : track) cameras.push_back(o.camera);
    std::sort(cameras.begin(), cameras.end());
    if (std::adjacent_find(cameras.begin(), cameras.end()) == cameras.end()) tracks.push_back(std::move(track));
  }
  report->tracks += static_cast<int>(tracks.size());
  return tracks;
}

// Direct linear transform on the fixed poses (normalised coordinates).
std::optional<Eigen::Vector3d> Dlt(const std::vector<View>& views, const Track& track) {
  Eigen::MatrixXd a(2 * track.size(), 4);
  for (std::size_t i = 0; i < track.size(); ++i) {
    const View& v = views[track[i].camera];
    Eigen::Matrix<double, 3, 4> p;
    p << v.r, v.t;
    const Eigen::Vector2d x = v.normalised[track[i].keypoint];
    a.row(2 * i) = x.x() * p.row(2) - p.row(0);
    a.row(2 * i + 1) = x.y() * p.row(2) - p.row(1);
  }
  const Eigen::Vector4d h = Eigen::JacobiSVD<Eigen::MatrixXd>(a, Eigen::ComputeFullV).matrixV().col(3);
  if (std::abs(h.w()) < 1e-12) return std::nullopt;
  return Eigen::Vector3d(h.head<3>() / h.w());
}

// The point seen from every observation of the track, or why not: in front of each camera,
// within the reprojection bound in each, and with rays at least the minimum angle apart.
enum class Verdict { kGood, kBehind, kReprojection, kAngle };

Verdict Check(const std::vector<View>& views, const Track& track, const Eigen::Vector3d& x, const RigTimeOptions& options) {
  double widest = 0;
  for (std::size_t i = 0; i < track.size(); ++i) {
    const View& v = views[track[i].camera];
    if (!((v.r * x + v.t).z() > 0)) return Verdict::kBehind;
    const Eigen::Vector2d e = ProjectRadial(v.pose, v.k, x) - v.features->pixels[track[i].keypoint];
    if (!(e.norm() < options.max_reprojection_pixels)) return Verdict::kReprojection;
    for (std::size_t j = 0; j < i; ++j) {
      const Eigen::Vector3d ra = x - v.centre, rb = x - views[track[j].camera].centre;
      widest = std::max(widest, std::acos(std::clamp(ra.normalized().dot(rb.normalized()), -1.0, 1.0)));
    }
  }
  return widest * 180 / M_PI >= options.min_angle_degrees ? Verdict::kGood : Verdict::kAngle;
}

// The rig cameras' observations by pixel (a hash grid of same_point_pixels cells), to find the
// existing point a new track lands on.
class PointIndex {
 public:
  PointIndex(const BundleProblem& problem, int cameras, double radius)
      : radius_(radius), cells_(cameras), cameras_of_(problem.points.size()) {
    for (const BundleObservation& o : problem.observations)
      if (o.pose < cameras) Add(o.pose, o.pixel, o.point);
  }
  void Add(int camera, const Eigen::Vector2d& pixel, int point) {
    cells_[camera][Key(std::floor(pixel.x() / radius_), std::floor(pixel.y() / radius_))].push_back({pixel, point});
    if (point >= static_cast<int>(cameras_of_.size())) cameras_of_.resize(point + 1);
    cameras_of_[point].push_back(camera);
  }
  std::vector<int> Near(int camera, const Eigen::Vector2d& pixel) const {
    std::vector<int> points;
    const double cx = std::floor(pixel.x() / radius_), cy = std::floor(pixel.y() / radius_);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        if (const auto it = cells_[camera].find(Key(cx + dx, cy + dy)); it != cells_[camera].end())
          for (const auto& [p, point] : it->second)
            if ((p - pixel).norm() <= radius_) points.push_back(point);
    return points;
  }
  bool Sees(int point, int camera) const {
    const auto& c = cameras_of_[point];
    return std::find(c.begin(), c.end(), camera) != c.end();
  }

 private:
  static std::int64_t Key(double x, double y) {
    return static_cast<std::int64_t>(x) * 1000003 + static_cast<std::int64_t>(y);
  }
  double radius_;
  std::vector<std::unordered_map<std::int64_t, std::vector<std::pair<Eigen::Vector2d, int>>>> cells_;
  std::vector<std::vector<int>> cameras_of_;
};

struct TimeContext {
  const std::vector<View>& views;
  const std::vector<int>& rig_intrinsics;
  const RigTimeOptions& options;
  BundleProblem* problem;
  PointIndex* index;
  RigTimeReport* report;
};

void AddObservation(const TimeContext& ctx, const TrackObservation& o, int point) {
  const Eigen::Vector2d& pixel = ctx.views[o.camera].features->pixels[o.keypoint];
  ctx.problem->observations.push_back({o.camera, ctx.rig_intrinsics[o.camera], point, pixel});
  ctx.index->Add(o.camera, pixel, point);
  ++ctx.report->observations_added;
}

// The existing point the track lands on: the one near most of its observations whose projection
// lies within the reprojection bound of every observation. -1: none (a new point).
int ExistingPoint(const TimeContext& ctx, const Track& track) {
  std::map<int, int> votes;
  for (const TrackObservation& o : track)
    for (int p : ctx.index->Near(o.camera, ctx.views[o.camera].features->pixels[o.keypoint])) ++votes[p];
  std::vector<std::pair<int, int>> ranked;
  for (const auto& [p, n] : votes) ranked.emplace_back(n, p);
  std::sort(ranked.rbegin(), ranked.rend());
  RigTimeOptions any_angle = ctx.options;
  any_angle.min_angle_degrees = 0;  // the point stands; only where it projects matters
  for (const auto& [n, p] : ranked)
    if (Check(ctx.views, track, ctx.problem->points[p], any_angle) == Verdict::kGood) return p;
  return -1;
}

void AddTrack(const TimeContext& ctx, const Track& track) {
  if (const int existing = ExistingPoint(ctx, track); existing >= 0) {
    bool extended = false;
    for (const TrackObservation& o : track) {
      if (ctx.index->Sees(existing, o.camera)) {
        ++ctx.report->repeats;
        continue;
      }
      AddObservation(ctx, o, existing);
      extended = true;
    }
    ctx.report->points_extended += extended;
    return;
  }
  const std::optional<Eigen::Vector3d> x = Dlt(ctx.views, track);
  const Verdict verdict = x ? Check(ctx.views, track, *x, ctx.options) : Verdict::kBehind;
  if (verdict == Verdict::kBehind) ++ctx.report->rejected_cheirality;
  if (verdict == Verdict::kReprojection) ++ctx.report->rejected_reprojection;
  if (verdict == Verdict::kAngle) ++ctx.report->rejected_angle;
  if (verdict != Verdict::kGood) return;
  const int point = static_cast<int>(ctx.problem->points.size());
  ctx.problem->points.push_back(*x);
  for (const TrackObservation& o : track) AddObservation(ctx, o, point);
  ++ctx.report->points_added;
}

// The rig cameras that have features at this time, with their current geometry.
std::vector<View> ViewsOf(const RigTimeFeatures& time, const std::vector<int>& rig_intrinsics,
                          const BundleProblem& problem) {
  std::vector<View> views(rig_intrinsics.size());
  for (std::size_t c = 0; c < views.size(); ++c) {
    View& v = views[c];
    v.pose = problem.poses[c];
    v.r = RotationOf(v.pose);
    v.t = problem.poses[c].translation;
    v.centre = -v.r.transpose() * v.t;
    v.k = problem.intrinsics[rig_intrinsics[c]];
    static const ViewFeatures kNone;
    v.features = c < time.views.size() ? &time.views[c] : &kNone;
    for (const Eigen::Vector2d& p : v.features->pixels) v.normalised.push_back(NormalisedRadial(v.k, p));
  }
  return views;
}

}  // namespace

ViewFeatures ExtractSift(const fs::path& image, int max_features) {
  const cv::Mat grey = cv::imread(image.string(), cv::IMREAD_GRAYSCALE);
  if (grey.empty()) Fail("{}: cannot read the image for SIFT (rig-time points)", image.string());
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  cv::SIFT::create(max_features)->detectAndCompute(grey, cv::noArray(), keypoints, descriptors);
  ViewFeatures features;
  // OpenCV puts the first pixel's centre at 0, COLMAP (whose model the bundle holds) at 0.5.
  for (const cv::KeyPoint& kp : keypoints) features.pixels.emplace_back(kp.pt.x + 0.5, kp.pt.y + 0.5);
  // RootSIFT (L1-normalised, square roots; COLMAP's default): Euclidean distance then compares
  // histograms as the Hellinger kernel does, which matches better.
  for (int r = 0; r < descriptors.rows; ++r) {
    float* d = descriptors.ptr<float>(r);
    float sum = 0;
    for (int i = 0; i < descriptors.cols; ++i) sum += std::abs(d[i]);
    for (int i = 0; i < descriptors.cols; ++i) d[i] = std::sqrt(std::abs(d[i]) / std::max(sum, 1e-12f));
  }
  features.descriptors = descriptors;
  return features;
}

std::vector<RigTimeFeatures> ExtractRigTimes(const Capture& capture, const std::vector<std::string>& camera_names,
                                             bool show_progress) {
  std::vector<const CaptureCamera*> cameras;
  for (const std::string& name : camera_names)
    for (const CaptureCamera& c : capture.cameras)
      if (c.name == name) cameras.push_back(&c);
  std::vector<RigTimeFeatures> times;
  if (cameras.size() != camera_names.size() || cameras.empty()) return times;
  for (std::size_t f = 0; f < cameras.front()->frames.size(); ++f) {
    RigTimeFeatures time;
    time.label = fmt::format("frame {}", cameras.front()->frames[f].index);
    for (const CaptureCamera* c : cameras) {
      const auto& brackets = c->frames.at(f).brackets;
      time.views.push_back(brackets.empty() ? ViewFeatures{} : ExtractSift(brackets[brackets.size() / 2]));
    }
    if (show_progress)
      fmt::print(stderr, "rig-time SIFT {}/{} ({} cameras)\n", f + 1, cameras.front()->frames.size(), cameras.size());
    times.push_back(std::move(time));
  }
  return times;
}

RigTimeReport AddRigTimePoints(const std::vector<RigTimeFeatures>& times, const std::vector<int>& rig_intrinsics,
                               BundleProblem* problem, const RigTimeOptions& options) {
  RigTimeReport report;
  report.times = static_cast<int>(times.size());
  const int cameras = static_cast<int>(rig_intrinsics.size());
  if (static_cast<int>(problem->poses.size()) < cameras)
    Fail("rig-time points: {} rig cameras but {} poses in the bundle problem", cameras, problem->poses.size());
  PointIndex index(*problem, cameras, options.same_point_pixels);
  const std::size_t first = problem->observations.size();
  for (const RigTimeFeatures& time : times) {
    const std::vector<View> views = ViewsOf(time, rig_intrinsics, *problem);
    const int kept_before = report.matches_kept;
    const std::vector<Track> tracks = TracksOfTime(views, options, &report);
    if (report.matches_kept == kept_before) {
      report.notes.push_back(fmt::format("rig-time points: {} skipped: no match between rig cameras passed the ratio "
                                         "test, the cross-check and the {:.1f} px Sampson bound", time.label,
                                         options.max_sampson_pixels));
      continue;
    }
    ++report.times_used;
    const TimeContext ctx{views, rig_intrinsics, options, problem, &index, &report};
    for (const Track& track : tracks) AddTrack(ctx, track);
  }
  report.rms_before = report.rms_after = ObservationRms(*problem, first);
  return report;
}

double ObservationRms(const BundleProblem& problem, std::size_t first) {
  double sum = 0;
  int n = 0;
  for (std::size_t i = first; i < problem.observations.size(); ++i) {
    const BundleObservation& o = problem.observations[i];
    const Eigen::Vector2d e =
        ProjectRadial(problem.poses[o.pose], problem.intrinsics[o.intrinsics], problem.points[o.point]) - o.pixel;
    if (std::isfinite(e.squaredNorm())) sum += e.squaredNorm(), ++n;
  }
  return n > 0 ? std::sqrt(sum / n) : 0.0;
}

}  // namespace hdr4d
