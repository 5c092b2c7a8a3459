#include "calibration/registration_ladder.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <optional>
#include <ranges>
#include <set>

#include "calibration/truth_comparison.h"
#include "core/geometry/colmap_model.h"
#include "core/util/error.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

std::vector<LadderRung> MakeLadder() {
  std::vector<LadderRung> rungs(5);
  rungs[0] = {"defaults", "COLMAP 3.8's settings", {}, {}, {}, false};
  rungs[1] = rungs[0];
  rungs[1].name = "more features";
  rungs[1].why = "16384 SIFT features, peak threshold 0.004";
  rungs[1].extract_args = {"--SiftExtraction.max_num_features", "16384", "--SiftExtraction.peak_threshold", "0.004"};
  rungs[2] = rungs[1];
  rungs[2].name = "DSP-SIFT";
  rungs[2].why = "domain-size pooling, affine shapes, guided matching";
  rungs[2].extract_args.insert(rungs[2].extract_args.end(), {"--SiftExtraction.domain_size_pooling", "1",
                                                             "--SiftExtraction.estimate_affine_shape", "1"});
  rungs[2].match_args = {"--SiftMatching.guided_matching", "1"};
  rungs[3] = rungs[2];
  rungs[3].name = "relaxed mapper";
  rungs[3].why = "abs_pose_min_num_inliers 12, abs_pose_min_inlier_ratio 0.1, init_min_num_inliers 30, min_num_matches 8";
  rungs[3].map_args = {"--Mapper.abs_pose_min_num_inliers", "12", "--Mapper.abs_pose_min_inlier_ratio", "0.1",
                       "--Mapper.init_min_num_inliers", "30", "--Mapper.min_num_matches", "8"};
  rungs[4] = rungs[3];
  rungs[4].name = "sequence frames";
  rungs[4].why = "the rig cameras' sequence frames (shortest, middle and longest bracket) beside their static images";
  rungs[4].sequence_frames = true;
  return rungs;
}

// What a model misses: rig cameras without a registered image, extra views not registered.
std::vector<std::string> Unregistered(const Capture& capture, const ColmapModel& model) {
  std::set<std::string> names;
  for (const auto& [id, image] : model.images) names.insert(image.name);
  auto folder_registered = [&](const std::string& folder) {
    for (const std::string& n : names)
      if (n.rfind(folder + "/", 0) == 0) return true;
    return false;
  };
  std::vector<std::string> missing;
  for (const CaptureCamera& camera : capture.cameras)
    if (!folder_registered(camera.name)) missing.push_back("camera " + camera.name);
  for (const fs::path& extra : capture.extra_images)
    if (!names.count("extra/" + extra.filename().string())) missing.push_back("extra/" + extra.filename().string());
  return missing;
}

// The fewest triangulated observations of any rig camera (over all its images: one pose).
int WeakestCameraObservations(const Capture& capture, const ColmapModel& model) {
  int weakest = -1;
  for (const CaptureCamera& camera : capture.cameras) {
    int count = 0;
    for (const auto& [id, image] : model.images)
      if (image.name.rfind(camera.name + "/", 0) == 0)
        for (const std::int64_t point : image.point3d_ids) count += model.points.count(point) ? 1 : 0;
    weakest = weakest < 0 ? count : std::min(weakest, count);
  }
  return std::max(weakest, 0);
}

// The images of the sequence rung: each rig camera's folder holds its static images and its
// sequence frames' middle brackets (one camera, one pose: the rig does not move), and extra/.
// Pairs worth matching among them: images of two different cameras (one camera's images share
// one pose: no baseline to triangulate from), and sequence frames only with frames of the same
// time (the actors move between frames). `groups[i]` = (camera, time: -1 static) of names[i].
std::vector<std::pair<std::string, std::string>> SequenceMatchPairs(const std::vector<std::string>& names,
                                                                    const std::vector<std::pair<int, int>>& groups) {
  std::vector<std::pair<std::string, std::string>> pairs;
  for (std::size_t i = 0; i < names.size(); ++i)
    for (std::size_t j = i + 1; j < names.size(); ++j)
      if (groups[i].first != groups[j].first && groups[i].second == groups[j].second)
        pairs.emplace_back(names[i], names[j]);
  return pairs;
}

fs::path SequenceImageFolder(const Capture& capture, const fs::path& folder,
                             std::vector<std::pair<std::string, std::string>>* pairs) {
  std::vector<std::string> names;
  std::vector<std::pair<int, int>> groups;  // (camera, frame index; -1 static), extra views camera -1
  fs::create_directories(folder);
  // File links only: COLMAP's image listing does not enter linked folders.
  for (const fs::path& image : capture.extra_images) {
    fs::create_directories(folder / "extra");
    fs::create_symlink(fs::absolute(image), folder / "extra" / image.filename());
    names.push_back("extra/" + image.filename().string());
    groups.emplace_back(-1 - static_cast<int>(names.size()), -1);  // each extra view its own pose
  }
  int camera_index = 0;
  for (const CaptureCamera& camera : capture.cameras) {
    const fs::path target = folder / camera.name;
    fs::create_directories(target);
    for (const fs::path& image : camera.static_images) {
      fs::create_symlink(fs::absolute(image), target / image.filename());
      names.push_back(camera.name + "/" + image.filename().string());
      groups.emplace_back(camera_index, -1);
    }
    // The shortest bracket finds features in the highlights, the longest in the shadows; a
    // dense bracket adds little beyond these three (and each image costs exhaustive matching).
    for (const CaptureFrame& frame : camera.frames) {
      std::vector<std::size_t> order(frame.brackets.size());
      for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
      if (frame.exposures.size() == order.size())
        std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return frame.exposures[a] < frame.exposures[b]; });
      const std::set<std::size_t> picks = {order.front(), order[order.size() / 2], order.back()};
      for (const std::size_t k : picks) {
        const fs::path& source = frame.brackets[k];
        fs::create_symlink(fs::absolute(source), target / ("seq_" + source.filename().string()));
        names.push_back(camera.name + "/seq_" + source.filename().string());
        groups.emplace_back(camera_index, frame.index);
      }
    }
    ++camera_index;
  }
  *pairs = SequenceMatchPairs(names, groups);
  return folder;
}

}  // namespace

const std::vector<LadderRung>& RegistrationLadder() {
  static const std::vector<LadderRung> ladder = MakeLadder();
  return ladder;
}

namespace {

// One rung's COLMAP run: the model folder (ColmapNoModel when COLMAP reconstructed nothing).
fs::path RunLadderRung(const Capture& capture, const fs::path& workspace,
                                      const ColmapRunOptions& options, std::size_t r) {
  const LadderRung& rung = RegistrationLadder()[r];
  ColmapRunOptions run = options;
  run.extract_args = rung.extract_args;
  run.match_args = rung.match_args;
  run.map_args = rung.map_args;
  const fs::path rung_dir = workspace / fmt::format("rung{}", r + 1);
  const fs::path images = rung.sequence_frames ? SequenceImageFolder(capture, rung_dir / "images", &run.match_pairs)
                                               : capture.root / "static";
  return RunColmap(images, rung_dir, run);
}

}  // namespace

namespace {

// A rig camera's image in a model: its static image, else its first.
const ColmapImage& RigCameraImage(const CaptureCamera& camera, const ColmapModel& model) {
  const ColmapImage* found = nullptr;
  for (const auto& [id, image] : model.images) {
    if (image.name.rfind(camera.name + "/", 0) != 0) continue;
    const bool sequence = image.name.find("/seq_") != std::string::npos;
    if (!found || (!sequence && found->name.find("/seq_") != std::string::npos)) found = &image;
  }
  if (!found) Fail("camera {}: no registered image in one of the models compared", camera.name);
  return *found;
}

// The second opinion on models that registered everything (the ladder's header). Rungs with the
// same features and images (3 and 4 differ only in the mapper) fail together: their agreement
// is weak evidence, kept only when nothing independent contradicts it.
class SecondOpinion {
 public:
  explicit SecondOpinion(const Capture& capture) : capture_(capture) {}
  bool Empty() const { return models_.empty(); }

  // Compares rung `r`'s model with the earlier ones: the earlier model that an independent rung
  // agrees with, or nothing (the model is kept for later rungs).
  std::optional<LadderResult> Offer(std::size_t r, const LadderResult& here, ColmapModel model,
                                    const std::vector<std::string>& attempts) {
    for (Entry& earlier : models_) {
      const ModelDisagreement apart = RigModelDisagreement(capture_, earlier.model, model);
      const bool independent = Independent(earlier.rung_index, r);
      comparisons_.push_back(fmt::format("rungs {} and {}: {:.2f} deg, focal {:.1f}%{}", earlier.result.rung,
                                         r + 1, apart.rotation_deg, 100 * apart.focal,
                                         independent ? "" : " (same features)"));
      if (apart.Agrees() && independent) {
        // Of the two, the model that registered more (extra views), the earlier at equal.
        const bool later = here.unregistered.size() < earlier.result.unregistered.size();
        return Conclude(later ? here : earlier.result, later ? earlier.result.rung : r + 1, attempts, false);
      }
      if (apart.Agrees() && !weak_agreement_) weak_agreement_ = {&earlier - models_.data(), r + 1};
      if (!apart.Agrees() && independent) independent_disagreement_ = true;
    }
    models_.push_back({r, here, std::move(model)});
    return std::nullopt;
  }

  // After the last rung: a model only rungs of the same features agreed on (said to be weak
  // evidence), the one model nothing could check if its cameras are strong, or the error when
  // the models disagree or the only one is weak.
  std::optional<LadderResult> Finish(const std::vector<std::string>& attempts) {
    if (weak_agreement_ && !independent_disagreement_)
      return Conclude(models_[weak_agreement_->first].result, weak_agreement_->second, attempts, true);
    if (models_.size() > 1)
      Fail("{}: COLMAP registered every rig camera on rungs {} of the registration ladder, but their models disagree on "
           "the rig ({}; right models agree within {} deg and {}% focal): at least one is mirrored or flattened and "
           "nothing tells which. Add hand-held views (static/extra/) that overlap neighbouring rig cameras, or give a "
           "model you trust with --colmap-model (tried: {})",
           capture_.root.string(),
           fmt::join(models_ | std::views::transform([](const Entry& e) { return e.result.rung; }), ", "),
           fmt::join(comparisons_, "; "), kModelAgreementDegrees, 100 * kModelAgreementFocal, fmt::join(attempts, "; "));
    if (models_.empty()) return std::nullopt;
    LadderResult only = models_.front().result;
    if (only.weakest_observations < kWeakCameraObservations)
      Fail("{}: only rung {} of the registration ladder registered every rig camera, and its weakest camera has {} "
           "triangulated observations (under {}): a model that weak and checked by no other rung is too often wrong "
           "(a 320x240 rig with 3 hand-held views came out 52 deg off). Add hand-held views (static/extra/) that "
           "overlap neighbouring rig cameras, or give a model you trust with --colmap-model (tried: {})",
           capture_.root.string(), only.rung, only.weakest_observations, kWeakCameraObservations,
           fmt::join(attempts, "; "));
    only.attempts = attempts;
    only.cross_check_weak = true;
    only.cross_check = fmt::format("the model of rung {} could not be checked: no other rung registered every rig "
                                   "camera", only.rung);
    return only;
  }

 private:
  struct Entry {
    std::size_t rung_index;
    LadderResult result;
    ColmapModel model;
  };

  static bool Independent(std::size_t a, std::size_t b) {
    const LadderRung& x = RegistrationLadder()[a];
    const LadderRung& y = RegistrationLadder()[b];
    return x.extract_args != y.extract_args || x.sequence_frames != y.sequence_frames;
  }

  LadderResult Conclude(LadderResult result, std::size_t other_rung, const std::vector<std::string>& attempts,
                        bool weak) const {
    result.attempts = attempts;
    result.cross_check_weak = weak;
    result.cross_check = fmt::format(
        "the model of rung {} was checked against rung {}'s: they agree{} (compared: {})", result.rung, other_rung,
        weak ? ", but rung " + std::to_string(other_rung) + " uses the same features, so the two can be wrong together"
             : "",
        fmt::join(comparisons_, "; "));
    return result;
  }

  const Capture& capture_;
  std::vector<Entry> models_;
  std::vector<std::string> comparisons_;
  std::optional<std::pair<std::ptrdiff_t, std::size_t>> weak_agreement_;  // (model index, agreeing rung)
  bool independent_disagreement_ = false;
};

}  // namespace

ModelDisagreement RigModelDisagreement(const Capture& capture, const ColmapModel& a, const ColmapModel& b) {
  ModelDisagreement d;
  std::vector<Eigen::Matrix3d> ra, rb;
  for (const CaptureCamera& camera : capture.cameras) {
    const ColmapImage& ia = RigCameraImage(camera, a);
    const ColmapImage& ib = RigCameraImage(camera, b);
    ra.push_back(ia.cam_from_world_rotation.normalized().toRotationMatrix());
    rb.push_back(ib.cam_from_world_rotation.normalized().toRotationMatrix());
    const double fa = a.cameras.at(ia.camera_id).Pinhole().fx, fb = b.cameras.at(ib.camera_id).Pinhole().fx;
    d.focal = std::max(d.focal, std::abs(fa / std::max(fb, 1e-9) - 1));
  }
  for (std::size_t i = 0; i < ra.size(); ++i)
    for (std::size_t j = i + 1; j < ra.size(); ++j)
      d.rotation_deg = std::max(d.rotation_deg, RotationAngleDegrees(ra[i] * ra[j].transpose(), rb[i] * rb[j].transpose()));
  return d;
}

LadderResult RegisterWithLadder(const Capture& capture, const fs::path& workspace, const ColmapRunOptions& options) {
  LadderResult best;
  std::optional<std::size_t> best_missing;
  std::optional<ColmapNoModel> last_error;
  SecondOpinion opinion(capture);
  const auto& ladder = RegistrationLadder();
  const bool have_frames = !capture.cameras.front().frames.empty();
  for (std::size_t r = 0; r < ladder.size(); ++r) {
    const LadderRung& rung = ladder[r];
    if (rung.sequence_frames && !have_frames) break;
    try {
      const fs::path folder = RunLadderRung(capture, workspace, options, r);
      ColmapModel model = ReadColmapModel(folder);
      const std::vector<std::string> missing = Unregistered(capture, model);
      const int weakest = WeakestCameraObservations(capture, model);
      best.attempts.push_back(fmt::format("{}. {}: {}, weakest camera {} observations", r + 1, rung.name,
                                          missing.empty() ? "all registered" : fmt::format("missing {}", fmt::join(missing, ", ")),
                                          weakest));
      LadderResult here = best;
      here.model_folder = folder;
      here.rung = static_cast<int>(r + 1);
      here.rung_name = rung.name;
      here.unregistered = missing;
      here.weakest_observations = weakest;
      // The defaults' model with strong cameras is taken as it is; any other that registered
      // everything needs another rung to agree.
      if (missing.empty() && opinion.Empty() && r == 0 && weakest >= kWeakCameraObservations) return here;
      // A model of every rig camera can give or get a second opinion (extra views only help).
      const bool rig_registered = std::none_of(missing.begin(), missing.end(), [](const std::string& m) {
        return m.rfind("camera ", 0) == 0;
      });
      if (rig_registered)
        if (auto agreed = opinion.Offer(r, here, std::move(model), best.attempts)) return *agreed;
      // Fewer missing wins; at equal, the model whose weakest camera has more observations.
      if (!best_missing || missing.size() < *best_missing ||
          (missing.size() == *best_missing && weakest > best.weakest_observations)) {
        best_missing = missing.size();
        const std::vector<std::string> attempts = best.attempts;
        best = here;
        best.attempts = attempts;
      }
    } catch (const ColmapNoModel& e) {
      best.attempts.push_back(fmt::format("{}. {}: no model", r + 1, rung.name));
      last_error = e;
    }
    spdlog::info("calibrate: COLMAP rung {} ({}) left {}; trying the next", r + 1, rung.name, best.attempts.back());
  }
  if (auto concluded = opinion.Finish(best.attempts)) return *concluded;
  if (!best_missing) throw *last_error;
  return best;
}

}  // namespace hdr4d
