// `hdr4d dataset split-val`: a scene with part of its training frames moved to a val split, so
// that `hdr4d train` can decide when to stop on held-out views (--stop-on-val, the default on a
// scene with a val split). The generators and the calibration write none (a split changes what
// a scene trains on), so this makes one for any scene in the reference layout, as a new folder:
// the original stays as it is.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>

namespace hdr4d {

// One moving camera overfits its views long before 20000 iterations: with one training time in
// 8 held back, the default's stop took 0.2-0.8 of the CPU of the full run on four datagen minis
// and scored better held out on seven of eight runs (docs/history/time-to-quality.md). datagen
// writes such a split for a monocular scene with enough times, and train suggests one.
inline constexpr int kMonocularValEvery = 8;
inline constexpr int kMinTimesForMonocularVal = 2 * kMonocularValEvery;  // two val times at least

struct ValSplitOptions {
  // > 0: every frame of every K-th distinct training time, the middle time of each run of K
  // (times K/2, K/2 + K, ...): a monocular capture loses one frame in K, a rig one time in K.
  int every_time = 0;
  // >= 0: every training frame of this camera_id (a fixed rig: one camera held back).
  int camera_id = -1;
  // > 0: every K-th training frame in file order, the middle one of each run of K (frames K/2,
  // K/2 + K, ...): a static capture whose frames are separate views loses one view in K.
  int every_frame = 0;
  // The option that set every_time, as the error messages name it.
  std::string every_time_flag = "--every-time";
};

struct ValSplitSummary {
  std::size_t moved = 0;  // training frames now in transforms_val.json
  std::size_t kept = 0;   // left in transforms_train.json
  std::string what;       // which frames moved, in words
};

// Reads the scene `dir` (transforms_train.json and transforms_test.json at its root, no val
// split) and writes the scene `out`: transforms_train.json without the chosen frames,
// transforms_val.json with them (each file keeps the original's top-level keys and every key of
// each frame), transforms_test.json as it was, and a link to every other entry of `dir`
// (images, HDR, point3d.ply). A nerfstudio scene (one transforms.json) gets a copy of that file
// with the chosen frames' file_path in val_filenames (and its test split written out as
// test_filenames where it was the implicit every 8th frame, which a list would otherwise end).
// `out` is built beside its place and moved there when complete; an existing non-empty `out` is
// refused. Throws hdr4d::Error naming the file and the problem
// for a scene that cannot be read, already has a val split, has no time or camera_id to choose
// by, or would keep no training frame.
ValSplitSummary SplitOffVal(const std::filesystem::path& dir,
                            const std::filesystem::path& out,
                            const ValSplitOptions& options);

// The same split made in place, for a scene folder still being built (hdr4d datagen
// --val-every, in its staging folder): transforms_val.json is written beside the others and the
// chosen frames leave transforms_train.json. The same refusals, and the reference layout only;
// `who` names the command in them.
ValSplitSummary SplitValInPlace(const std::filesystem::path& dir,
                                const ValSplitOptions& options,
                                const char* who);

}  // namespace hdr4d
