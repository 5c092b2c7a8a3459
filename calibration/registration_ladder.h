// Registration that does not give up: when COLMAP's defaults leave a rig camera or an extra
// view unregistered, calibrate climbs a ladder of settings, each rung keeping the ones before:
//   1. defaults      COLMAP 3.8 as is (SIFT already on the upsampled image, first_octave -1)
//   2. more features twice the features (16384) and a lower peak threshold (0.004): small or
//                    low-contrast images give SIFT few keypoints
//   3. DSP-SIFT      domain-size pooling and affine-shape estimation (descriptors that survive
//                    viewpoint change) and guided matching (more inliers per pair)
//   4. relaxed       the mapper registers an image from 12 inliers (30) at a 10% inlier ratio
//                    (25%), starts from 30 inliers (100) and keeps pairs of 8 matches (15)
//   5. sequence      the rig cameras' own sequence frames (shortest, middle and longest bracket
//                    of each) join their static images in the camera's folder (one pose, one
//                    set of intrinsics): the scene's static parts match across cameras, the
//                    short and long brackets add features in highlights and shadows, and the
//                    actors seen by every camera at one time add cross-camera points
// The first rung that registers every rig camera and every extra view wins; otherwise the one
// that registered most (at equal, the one whose weakest camera has more observations).
// A model of a hard capture (one that the defaults did not register, or with a rig camera
// under kWeakCameraObservations) is not taken on its own word: at low resolution with few views
// COLMAP can build a wrong model that fits its tracks to under 1 px (a 320x240 rig with 3
// hand-held views, one seed: once mirrored, every camera 135-179 deg off; in another run of
// the same capture flattened, focal lengths 13-19% short). So the ladder climbs on for a second
// opinion and keeps the earliest model that another rung's model agrees with (the rig cameras'
// relative rotations within kModelAgreementDegrees and their focal lengths within
// kModelAgreementFocal). Rungs 3 and 4 share their features and fail together (seed 21: both
// flattened alike), so their agreement alone is weak evidence: kept with a warning unless an
// independent rung contradicts it. Models that registered every rig camera but not every extra
// view take part too. When the models disagree and none is agreed on, or the only model has a
// weak camera, calibrate stops with an error naming the rungs instead of writing a model it
// cannot trust. A camera
// that no rung registers fails with the error of RigFromColmap (it truly shares no view). The
// report names the rung and each rung's weakest camera. A rig camera with fewer than
// kWeakCameraObservations triangulated observations (no hand-held views around it) is named in
// the report: too few to pin its focal length and distortion. Going on to rung 5 for such a
// camera was measured and made the geometry worse (docs/history/calibration.md, fourth pass):
// COLMAP gives each sequence frame its own pose, and those poses drift.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "calibration/capture.h"
#include "calibration/colmap_driver.h"
#include "core/geometry/colmap_model.h"

namespace hdr4d {

// Below this many triangulated observations a rig camera counts as weakly registered.
constexpr int kWeakCameraObservations = 300;
// Two of COLMAP's models agree when every pair of rig cameras' relative rotation is within this
// of the other's, and every rig camera's focal lengths within kModelAgreementFocal. Measured on
// the raw models of six 320x240 rigs with 3 hand-held views (docs/history/calibration.md, ninth
// pass): models that the refinement takes to the truth differ by 0.04-3.0 deg and 1-17% focal
// (COLMAP's focal lengths are 1-21% off there before the refinement); wrong ones by 4-49 deg
// or 39% focal and more.
constexpr double kModelAgreementDegrees = 5.0;
constexpr double kModelAgreementFocal = 0.25;

struct LadderRung {
  std::string name, why;
  std::vector<std::string> extract_args, match_args, map_args;
  bool sequence_frames = false;
};

// The rungs above, in order.
const std::vector<LadderRung>& RegistrationLadder();

struct LadderResult {
  std::filesystem::path model_folder;
  int rung = 0;  // 1-based, the rung whose model is returned
  std::string rung_name;
  std::vector<std::string> attempts;    // one line per rung tried: what it registered
  std::vector<std::string> unregistered;  // rig cameras / extra views still missing (best effort)
  int weakest_observations = 0;  // the fewest triangulated observations of one rig camera
  // For a model that needed a second opinion: which rung's model it was checked against, or
  // why it could not be checked; empty for a model that needed no second opinion.
  std::string cross_check;
  // The check was weak: only a rung of the same features agreed, or none could check (calibrate
  // warns).
  bool cross_check_weak = false;
};

struct ModelDisagreement {
  double rotation_deg = 0;  // the largest, over pairs of rig cameras, between relative rotations
  double focal = 0;         // the largest |f_a / f_b - 1| of a rig camera
  bool Agrees() const { return rotation_deg <= kModelAgreementDegrees && focal <= kModelAgreementFocal; }
};

// How far two models of one capture are apart on the rig cameras (blind to the similarity
// between the models). A rig camera's pose and camera are its static image's (its first image
// when it has none). Throws hdr4d::Error when a rig camera has no image in either model.
ModelDisagreement RigModelDisagreement(const Capture& capture, const ColmapModel& a, const ColmapModel& b);

// Runs the ladder in `workspace` (a folder per rung) until everything registers. Throws the
// last rung's error when no rung reconstructs anything, hdr4d::Error when COLMAP cannot run.
LadderResult RegisterWithLadder(const Capture& capture, const std::filesystem::path& workspace,
                                const ColmapRunOptions& options);

}  // namespace hdr4d
