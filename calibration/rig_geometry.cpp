#include "calibration/rig_geometry.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "calibration/undistort.h"
#include "core/util/error.h"
#include "core/files/json_util.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

std::string FolderOf(const std::string& image_name) {
  const auto slash = image_name.find('/');
  return slash == std::string::npos ? std::string() : image_name.substr(0, slash);
}

BundleIntrinsics IntrinsicsOf(const ColmapCamera& camera) {
  const PinholeIntrinsics k = camera.Pinhole();
  const Eigen::Vector2d radial = camera.Radial();
  return {0.5 * (k.fx + k.fy), k.cx, k.cy, radial.x(), radial.y()};
}

BundlePose PoseOf(const ColmapImage& image) {
  BundlePose pose;
  const Eigen::AngleAxisd aa(image.cam_from_world_rotation.normalized());
  pose.rotation = aa.angle() * aa.axis();
  pose.translation = image.cam_from_world_translation;
  return pose;
}

double Percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  const std::size_t i = static_cast<std::size_t>(q * (values.size() - 1));
  std::nth_element(values.begin(), values.begin() + i, values.end());
  return values[i];
}

}  // namespace

const RigCamera* Rig::Find(const std::string& name) const {
  for (const RigCamera& c : cameras)
    if (c.name == name) return &c;
  return nullptr;
}

namespace {

// The bundle problem of a COLMAP model: one pose per rig camera (all its static images share
// it), one per extra image, COLMAP's intrinsics per camera (or a board's, held), every point.
struct RigProblem {
  BundleProblem problem;
  std::map<int, int> pose_of_image;         // COLMAP image id -> bundle pose
  std::map<int, int> intrinsics_of_camera;  // COLMAP camera id -> bundle intrinsics
  std::vector<int> rig_intrinsics;          // rig camera -> bundle intrinsics
  std::vector<std::int64_t> point_ids;

  int IntrinsicsIndex(const ColmapModel& model, int camera_id) {
    auto [it, added] = intrinsics_of_camera.emplace(camera_id, static_cast<int>(problem.intrinsics.size()));
    if (added) problem.intrinsics.push_back(IntrinsicsOf(model.cameras.at(camera_id)));
    return it->second;
  }
};

// With --shared-intrinsics: the block of an earlier rig camera of the same image size, else -1.
int SharedBlock(const std::vector<RigCamera>& earlier, const RigCamera& camera, const RigOptions& options,
                const RigProblem& rp) {
  if (!options.shared_intrinsics) return -1;
  for (std::size_t e = 0; e < earlier.size(); ++e)
    if (!earlier[e].board_intrinsics && earlier[e].width == camera.width && earlier[e].height == camera.height)
      return rp.rig_intrinsics[e];
  return -1;
}

RigCamera AddRigCamera(const ColmapModel& model, const std::string& name, std::size_t c,
                       const RigOptions& options, const std::vector<RigCamera>* earlier, RigProblem* rp) {
  RigCamera camera;
  camera.name = name;
  int first = -1;
  for (const auto& [id, image] : model.images) {
    if (FolderOf(image.name) != camera.name) continue;
    if (first < 0) {
      first = id;
      rp->problem.poses.push_back(PoseOf(image));
      rp->problem.poses.back().fixed = c == 0;  // the gauge
    }
    rp->pose_of_image[id] = static_cast<int>(c);
    ++camera.static_images_registered;
  }
  if (first < 0)
    Fail("camera {}: none of its static images (static/{}/) was registered by COLMAP; it "
         "needs views that overlap the other cameras'", camera.name, camera.name);
  const ColmapCamera& colmap_camera = model.cameras.at(model.images.at(first).camera_id);
  camera.width = colmap_camera.width;
  camera.height = colmap_camera.height;
  if (const auto board = options.board_intrinsics.find(camera.name); board != options.board_intrinsics.end()) {
    // Its own block, held: the board's intrinsics are the better measurement.
    rp->rig_intrinsics.push_back(static_cast<int>(rp->problem.intrinsics.size()));
    rp->problem.intrinsics.push_back(board->second);
    rp->problem.intrinsics.back().fixed = true;
    camera.board_intrinsics = true;
  } else if (const int shared = SharedBlock(*earlier, camera, options, *rp); shared >= 0) {
    rp->rig_intrinsics.push_back(shared);
  } else {
    rp->rig_intrinsics.push_back(rp->IntrinsicsIndex(model, colmap_camera.id));
  }
  return camera;
}

void AddPoints(const ColmapModel& model, std::size_t rig_cameras, RigProblem* rp, Rig* rig) {
  for (const auto& [id, point] : model.points) {
    const int index = static_cast<int>(rp->problem.points.size());
    rp->problem.points.push_back(point.xyz);
    rp->point_ids.push_back(id);
    rig->visibility.emplace_back();
    std::vector<int>& seen_by = rig->visibility.back();
    for (const auto& [image_id, idx] : point.track) {
      const ColmapImage& image = model.images.at(image_id);
      const int pose = rp->pose_of_image.at(image_id);
      const bool rig_pose = pose < static_cast<int>(rig_cameras);
      if (rig_pose && std::find(seen_by.begin(), seen_by.end(), pose) == seen_by.end()) seen_by.push_back(pose);
      const int k = rig_pose ? rp->rig_intrinsics[pose] : rp->IntrinsicsIndex(model, image.camera_id);
      rp->problem.observations.push_back({pose, k, index, image.points2d[idx]});
    }
  }
}

// Normalise: the median point to the origin, 90% of the points within radius 1.
void Normalise(const std::vector<Eigen::Vector3d>& points, Rig* rig) {
  std::vector<double> coords[3], radii;
  for (const auto& p : points)
    for (int a = 0; a < 3; ++a) coords[a].push_back(p[a]);
  for (int a = 0; a < 3; ++a) rig->centre[a] = Percentile(coords[a], 0.5);
  for (const auto& p : points) radii.push_back((p - rig->centre).norm());
  const double r90 = Percentile(radii, 0.9);
  rig->scale = r90 > 1e-12 ? 1.0 / r90 : 1.0;
}

void ExportCamera(const BundlePose& pose, const BundleIntrinsics& intrinsics, const Rig& rig,
                  const RigOptions& options, RigCamera* camera) {
  camera->intrinsics = intrinsics;
  const double angle = pose.rotation.norm();
  const Eigen::Matrix3d r = angle > 0 ? Eigen::AngleAxisd(angle, pose.rotation / angle).toRotationMatrix()
                                      : Eigen::Matrix3d::Identity();
  Eigen::Matrix4d cam_from_world = Eigen::Matrix4d::Identity();
  cam_from_world.topLeftCorner<3, 3>() = r;
  cam_from_world.topRightCorner<3, 1>() = rig.scale * (r * rig.centre + pose.translation);
  const Camera cam = Camera::FromWorldFromCamCv(
      PinholeIntrinsics{intrinsics.f, intrinsics.f, intrinsics.cx, intrinsics.cy, camera->width, camera->height},
      RigidInverse(cam_from_world));
  camera->world_from_cam_gl = cam.world_from_cam_gl;
  camera->max_distortion_pixels = MaxDistortionPixels(intrinsics, camera->width, camera->height);
  camera->undistort = camera->max_distortion_pixels > options.undistort_threshold_pixels;
}

// Per intrinsics block of the rig cameras: the sum of squared residuals, each capped at 3 px
// so that COLMAP's remaining outliers do not decide, and the number of observations.
std::map<int, std::pair<double, int>> CappedSse(const BundleProblem& problem, const std::vector<int>& rig_intrinsics) {
  std::map<int, std::pair<double, int>> sse;
  for (const BundleObservation& o : problem.observations) {
    if (o.pose >= static_cast<int>(rig_intrinsics.size())) continue;
    const Eigen::Vector2d e = ProjectRadial(problem.poses[o.pose], problem.intrinsics[o.intrinsics],
                                            problem.points[o.point]) - o.pixel;
    const double e2 = std::isfinite(e.squaredNorm()) ? std::min(e.squaredNorm(), 9.0) : 9.0;
    auto& [sum, n] = sse[rig_intrinsics[o.pose]];
    sum += e2, ++n;
  }
  return sse;
}

// Model selection of the radial terms per intrinsics block, nested: none, k1, k1 and k2. Each
// smaller model is refined once more with its terms held at 0 (everything else free, so that one
// camera's real distortion does not pull the shared points) and the model of least BIC is kept,
// BIC = N ln(SSE / N) + p ln N over the N = 2n residual components of the block's n
// observations (p = 0, 1, 2). k2 alone (k1 = 0) is no lens's model and not tried. Blocks that
// drop terms are zeroed and held in `rp` (to be refined again). Returns whether any dropped.
struct DistortionChoice {
  int terms = 2;
  double score = 0;  // BIC(none) - BIC(chosen)
};

DistortionChoice ChooseDistortion(const RigProblem& rp, int block, double sse2, int n) {
  std::array<double, 3> sse{0, 0, sse2};
  for (int terms : {0, 1}) {
    BundleProblem smaller = rp.problem;
    BundleIntrinsics& k = smaller.intrinsics[block];
    k.k2 = 0;
    k.hold_k2 = true;
    if (terms == 0) k.k1 = 0, k.hold_distortion = true;
    RefineBundle(&smaller);
    sse[terms] = CappedSse(smaller, rp.rig_intrinsics).at(block).first;
  }
  const double big_n = 2.0 * std::max(n, 1);
  const double floor = 1e-8 * big_n;  // (0.1 mpx)^2 per component: exact synthetic data
  auto bic = [&](int p) { return big_n * std::log((sse[p] + floor) / big_n) + p * std::log(big_n); };
  DistortionChoice choice{0, 0};
  for (int p : {1, 2})
    if (bic(p) < bic(choice.terms)) choice.terms = p;
  choice.score = bic(0) - bic(choice.terms);
  return choice;
}

bool SelectDistortion(RigProblem* rp, std::vector<RigCamera>* cameras) {
  const auto with_sse = CappedSse(rp->problem, rp->rig_intrinsics);
  std::map<int, DistortionChoice> choice_of;  // per block
  for (const auto& [block, sse_n] : with_sse)
    if (!rp->problem.intrinsics[block].fixed && !rp->problem.intrinsics[block].hold_distortion)
      choice_of[block] = ChooseDistortion(*rp, block, sse_n.first, sse_n.second);
  bool dropped = false;
  for (std::size_t c = 0; c < cameras->size(); ++c) {
    const auto it = choice_of.find(rp->rig_intrinsics[c]);
    if (it == choice_of.end()) continue;
    RigCamera& camera = (*cameras)[c];
    camera.distortion_score = it->second.score;
    camera.distortion_terms = it->second.terms;
    camera.distortion_kept = it->second.terms > 0;
    BundleIntrinsics& k = rp->problem.intrinsics[it->first];
    if (it->second.terms < 2 && !k.hold_k2) dropped = true, k.k2 = 0, k.hold_k2 = true;
    if (it->second.terms == 0) k.k1 = 0, k.hold_distortion = true;
  }
  return dropped;
}

// Sum of capped squared residuals and observations over `blocks`.
std::pair<double, int> GroupSse(const BundleProblem& problem, const std::vector<int>& rig_intrinsics,
                                const std::vector<int>& blocks) {
  std::pair<double, int> total{0.0, 0};
  for (const auto& [block, sse_n] : CappedSse(problem, rig_intrinsics))
    if (std::find(blocks.begin(), blocks.end(), block) != blocks.end())
      total.first += sse_n.first, total.second += sse_n.second;
  return total;
}

// Per image size, the rig cameras' own (unfixed, unshared) intrinsics blocks; when one focal
// length for all of them has a lower BIC than one each (N ln(SSE / N) + p ln N, N = 2n residual
// components, C - 1 parameters fewer), `rp` takes the shared solution. Returns whether any did.
bool SelectSharedFocal(RigProblem* rp, std::vector<RigCamera>* cameras, std::vector<std::string>* notes) {
  std::map<std::pair<int, int>, std::vector<int>> blocks_of_size;
  for (std::size_t c = 0; c < cameras->size(); ++c) {
    const int block = rp->rig_intrinsics[c];
    std::vector<int>& blocks = blocks_of_size[{(*cameras)[c].width, (*cameras)[c].height}];
    const bool own = std::count(rp->rig_intrinsics.begin(), rp->rig_intrinsics.end(), block) == 1;
    if (own && !rp->problem.intrinsics[block].fixed) blocks.push_back(block);
  }
  bool shared_any = false;
  int group = 0;
  for (const auto& [size, blocks] : blocks_of_size) {
    if (blocks.size() < 2) continue;
    BundleProblem shared = rp->problem;
    for (int b : blocks) shared.intrinsics[b].focal_group = group;
    RefineBundle(&shared);
    const auto [sse_each, n] = GroupSse(rp->problem, rp->rig_intrinsics, blocks);
    const double sse_shared = GroupSse(shared, rp->rig_intrinsics, blocks).first;
    const double big_n = 2.0 * std::max(n, 1), floor = 1e-8 * big_n;
    const double gain = big_n * std::log((sse_shared + floor) / (sse_each + floor)) -
                        (static_cast<double>(blocks.size()) - 1) * std::log(big_n);  // BIC(shared) - BIC(each)
    notes->push_back(fmt::format(
        "{}x{} cameras: one focal length for {} of them {} (BIC {:+.1f} against one each; RMS {:.3f} against "
        "{:.3f} px)", size.first, size.second, blocks.size(), gain <= 0 ? "explains the observations as well" :
        "does not explain the observations: each keeps its own", gain, std::sqrt(sse_shared / std::max(n, 1)),
        std::sqrt(sse_each / std::max(n, 1))));
    if (gain > 0) continue;
    rp->problem = std::move(shared);
    for (std::size_t c = 0; c < cameras->size(); ++c)
      if (std::find(blocks.begin(), blocks.end(), rp->rig_intrinsics[c]) != blocks.end())
        (*cameras)[c].focal_shared = true;
    shared_any = true;
    ++group;
  }
  return shared_any;
}

// The report says why a camera ends with a larger reprojection RMS than COLMAP's.
void NoteWorseCameras(const Rig& rig, std::vector<std::string>* notes) {
  for (const RigCamera& c : rig.cameras) {
    if (!(c.rms_after > c.rms_before * 1.001)) continue;
    notes->push_back(fmt::format(
        "camera {}: reprojection RMS {:.3f} px after the refinement, {:.3f} px before: {}", c.name, c.rms_after,
        c.rms_before,
        !c.distortion_kept ? "its distortion is held at 0, as it did not explain the observations beyond noise "
                             "(COLMAP's k1, k2 fitted some of the noise)"
                           : "the refinement minimises a Huber loss (residuals beyond 1 px count linearly), which "
                             "weighs COLMAP's remaining outliers less than the RMS does"));
  }
}

// The rig cameras' intrinsics blocks that the refinement may change, each once.
std::vector<int> FreeRigBlocks(const RigProblem& rp) {
  std::vector<int> blocks;
  for (int b : rp.rig_intrinsics)
    if (!rp.problem.intrinsics[b].fixed && std::find(blocks.begin(), blocks.end(), b) == blocks.end())
      blocks.push_back(b);
  return blocks;
}

// The focal restarts, run once the models are chosen (shared focal lengths, radial terms) so that
// every start has the same parameters and the costs compare: COLMAP's poses and focal lengths
// scaled, its distortion where the model keeps it (0 where not), points re-triangulated. Before
// the selections each start's focal length traded against COLMAP's k1, k2 (all free), and the
// least cost there did not carry over to the model kept (issue 54, 1280x720 rig). The
// selection's own solution stays unless a restart ends at a strictly lower cost.
void RestartFromFocalLengths(const RigOptions& options, const BundleProblem& colmap_start, RigProblem* rp, Rig* rig,
                             BundleReport* report) {
  BundleProblem start = colmap_start;
  for (std::size_t i = 0; i < start.intrinsics.size(); ++i) {
    const BundleIntrinsics& chosen = rp->problem.intrinsics[i];
    BundleIntrinsics& k = start.intrinsics[i];
    k.focal_group = chosen.focal_group, k.hold_distortion = chosen.hold_distortion, k.hold_k2 = chosen.hold_k2;
    if (k.hold_distortion) k.k1 = chosen.k1, k.k2 = chosen.k2;
    if (k.hold_k2) k.k2 = chosen.k2;
  }
  BundleReport restarted;
  FocalStartReport starts = RefineFromFocalStarts(&start, FreeRigBlocks(*rp), options.focal_starts, {}, &restarted);
  starts.selection_cost = RobustCost(rp->problem, BundleOptions{}.huber_pixels);
  starts.selection_focal = rp->problem.intrinsics[FreeRigBlocks(*rp).front()].f;
  rig->refinement_iterations += restarted.iterations;
  if (starts.starts[starts.kept].cost < starts.selection_cost) {
    rp->problem = std::move(start);
    const std::vector<double> rms_in = report->rms_before;
    *report = restarted;
    report->rms_before = rms_in;
  } else {
    starts.kept = -1;
  }
  rig->focal_starts = std::move(starts);
}

// COLMAP's model refined, then the model selections (shared focal length, distortion terms),
// each followed by a refinement. The report's rms_before is of the problem as it came in.
BundleReport RefineAndSelect(const RigOptions& options, RigProblem* rp, Rig* rig) {
  BundleOptions bundle;
  if (!options.refine) bundle.max_iterations = 0;  // the residuals of COLMAP's model, unchanged
  const BundleProblem colmap_start = rp->problem;
  BundleReport report = RefineBundle(&rp->problem, bundle);
  rig->refinement_iterations += report.iterations;
  if (!options.refine) rig->notes.push_back("the rig is COLMAP's model as it is (--no-refinement)");
  // One focal length for alike cameras is decided first, with every camera's k1, k2 free: a
  // camera's own focal length absorbs much of its radial distortion (one pose each), a shared
  // one cannot, so the distortion selection that follows sees it.
  const std::vector<double> rms_in = report.rms_before;
  auto refine_again = [&] {
    report = RefineBundle(&rp->problem);
    report.rms_before = rms_in;
    rig->refinement_iterations += report.iterations;
  };
  if (options.refine && options.select_shared_focal && SelectSharedFocal(rp, &rig->cameras, &rig->notes))
    refine_again();
  if (options.refine && options.select_distortion && SelectDistortion(rp, &rig->cameras)) refine_again();
  if (options.refine && !options.focal_starts.empty() && !FreeRigBlocks(*rp).empty())
    RestartFromFocalLengths(options, colmap_start, rp, rig, &report);
  return report;
}

// Rig-time points are matched and triangulated under the geometry that COLMAP's points alone
// refine to (a first pass, its notes and choices dropped): COLMAP's own intrinsics can carry a
// distortion fitted to noise that moves the image borders by pixels, and a Sampson bound under
// them would keep the matches that agree with it and drop the border matches that show it
// wrong. The points join the first pass's geometry, with every intrinsics choice reopened, and
// the refinement and model selections run again on everything.
BundleReport RefineWithRigTimePoints(const RigOptions& options, RigProblem* rp, Rig* rig) {
  BundleProblem colmap_only = rp->problem;
  const std::vector<double> colmap_rms = RefineBundle(&colmap_only, {.max_iterations = 0}).rms_before;
  {
    Rig first_rig = *rig;
    RigProblem first = *rp;
    RefineAndSelect(options, &first, &first_rig);
    rig->focal_starts = first_rig.focal_starts;
    rp->problem.poses = first.problem.poses;
    rp->problem.points = first.problem.points;
    for (std::size_t i = 0; i < rp->problem.intrinsics.size(); ++i) {
      const BundleIntrinsics& refined = first.problem.intrinsics[i];
      BundleIntrinsics& k = rp->problem.intrinsics[i];
      if (!k.fixed) k.f = refined.f, k.k1 = refined.k1, k.k2 = refined.k2;
    }
  }
  rig->rig_time = AddRigTimePoints(options.rig_times, rp->rig_intrinsics, &rp->problem, options.rig_time);
  rig->notes.insert(rig->notes.end(), rig->rig_time->notes.begin(), rig->rig_time->notes.end());
  // The focal restarts ran in the first pass; the points start from its geometry.
  RigOptions again = options;
  again.focal_starts.clear();
  BundleReport report = RefineAndSelect(again, rp, rig);
  report.rms_before = colmap_rms;
  return report;
}

}  // namespace

Rig RigFromColmap(const ColmapModel& model, const std::vector<std::string>& camera_names,
                  const RigOptions& options) {
  Rig rig;
  RigProblem rp;
  // Rig cameras first (pose i = camera i), all their images sharing one pose.
  for (std::size_t c = 0; c < camera_names.size(); ++c)
    rig.cameras.push_back(AddRigCamera(model, camera_names[c], c, options, &rig.cameras, &rp));
  // Extra (hand-held) images: a pose each; they constrain the points and are then dropped.
  for (const auto& [id, image] : model.images) {
    if (rp.pose_of_image.count(id)) continue;
    rp.pose_of_image[id] = static_cast<int>(rp.problem.poses.size());
    rp.problem.poses.push_back(PoseOf(image));
    ++rig.extra_images_registered;
  }
  AddPoints(model, camera_names.size(), &rp, &rig);
  if (rp.problem.observations.empty()) Fail("COLMAP's model has no 3D points to refine the rig with");
  const std::size_t colmap_points = rp.problem.points.size(), colmap_observations = rp.problem.observations.size();
  BundleReport report;
  if (options.rig_times.empty() || !options.refine) {
    if (!options.rig_times.empty()) rig.notes.push_back("rig-time points are not used without the refinement");
    report = RefineAndSelect(options, &rp, &rig);
  } else {
    report = RefineWithRigTimePoints(options, &rp, &rig);
    rig.rig_time->rms_after = ObservationRms(rp.problem, colmap_observations);
    // The cameras' RMS after, like before, over COLMAP's observations: comparable figures.
    BundleProblem colmap_only = rp.problem;
    colmap_only.observations.resize(colmap_observations);
    report.rms_after = RefineBundle(&colmap_only, {.max_iterations = 0}).rms_before;
  }
  rp.problem.points.resize(colmap_points);  // the added points constrained the geometry; the scene is COLMAP's
  Normalise(rp.problem.points, &rig);
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    RigCamera& camera = rig.cameras[c];
    camera.rms_before = report.rms_before[c];
    camera.rms_after = report.rms_after[c];
    camera.observations = report.observations[c];
    ExportCamera(rp.problem.poses[c], rp.problem.intrinsics[rp.rig_intrinsics[c]], rig, options, &camera);
  }
  NoteWorseCameras(rig, &rig.notes);
  for (std::size_t i = 0; i < rp.problem.points.size(); ++i) {
    rig.points.positions.push_back(((rp.problem.points[i] - rig.centre) * rig.scale).cast<float>());
    rig.points.colors.push_back(model.points.at(rp.point_ids[i]).rgb);
  }
  return rig;
}

void WriteRigJson(const fs::path& path, const Rig& rig) {
  nlohmann::json doc;
  doc["model_source"] = rig.model_source;
  doc["intrinsics_source"] = rig.intrinsics_source;
  doc["metres_per_unit"] = rig.metres_per_unit;
  doc["normalisation"] = {{"centre", {rig.centre.x(), rig.centre.y(), rig.centre.z()}},
                          {"scale", rig.scale}};
  doc["extra_images_registered"] = rig.extra_images_registered;
  doc["refinement_iterations"] = rig.refinement_iterations;
  for (const RigCamera& c : rig.cameras) {
    nlohmann::json m = nlohmann::json::array();
    for (int r = 0; r < 4; ++r) m.push_back({c.world_from_cam_gl(r, 0), c.world_from_cam_gl(r, 1),
                                             c.world_from_cam_gl(r, 2), c.world_from_cam_gl(r, 3)});
    doc["cameras"].push_back({{"name", c.name},
                              {"width", c.width},
                              {"height", c.height},
                              {"f", c.intrinsics.f},
                              {"cx", c.intrinsics.cx},
                              {"cy", c.intrinsics.cy},
                              {"k1", c.intrinsics.k1},
                              {"k2", c.intrinsics.k2},
                              {"transform_matrix", m},
                              {"rms_before", c.rms_before},
                              {"rms_after", c.rms_after},
                              {"observations", c.observations},
                              {"static_images_registered", c.static_images_registered},
                              {"max_distortion_pixels", c.max_distortion_pixels},
                              {"undistort", c.undistort},
                              {"board_intrinsics", c.board_intrinsics}});
  }
  WriteJsonFile(path, doc);
}

Rig ReadRigJson(const fs::path& path) {
  const nlohmann::json doc = ReadJsonFile(path);
  Rig rig;
  try {
    rig.model_source = doc.at("model_source").get<std::string>();
    rig.intrinsics_source = doc.value("intrinsics_source", rig.intrinsics_source);
    rig.metres_per_unit = doc.value("metres_per_unit", 0.0);
    const auto& n = doc.at("normalisation");
    for (int a = 0; a < 3; ++a) rig.centre[a] = n.at("centre").at(a).get<double>();
    rig.scale = n.at("scale").get<double>();
    rig.extra_images_registered = doc.value("extra_images_registered", 0);
    rig.refinement_iterations = doc.value("refinement_iterations", 0);
    for (const auto& j : doc.at("cameras")) {
      RigCamera c;
      c.name = j.at("name").get<std::string>();
      c.width = j.at("width").get<int>();
      c.height = j.at("height").get<int>();
      c.intrinsics = {j.at("f").get<double>(), j.at("cx").get<double>(), j.at("cy").get<double>(),
                      j.at("k1").get<double>(), j.at("k2").get<double>()};
      for (int r = 0; r < 4; ++r)
        for (int k = 0; k < 4; ++k) c.world_from_cam_gl(r, k) = j.at("transform_matrix").at(r).at(k).get<double>();
      c.rms_before = j.at("rms_before").get<double>();
      c.rms_after = j.at("rms_after").get<double>();
      c.observations = j.at("observations").get<int>();
      c.static_images_registered = j.at("static_images_registered").get<int>();
      c.max_distortion_pixels = j.at("max_distortion_pixels").get<double>();
      c.undistort = j.at("undistort").get<bool>();
      c.board_intrinsics = j.value("board_intrinsics", false);
      rig.cameras.push_back(c);
    }
  } catch (const nlohmann::json::exception& e) {
    Fail("{}: {}", path.string(), e.what());
  }
  return rig;
}

}  // namespace hdr4d
