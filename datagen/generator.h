// `hdr4d datagen`: renders a procedural scene with Blender (Cycles on the CPU, linear float EXR),
// then makes the dataset around it: multi-exposure LDR images through core's LDR synthesis
// (exposure, camera response, sensor noise, 8 bits), transforms_{train,test}.json in the layout
// of ARCHITECTURE §3, point3d.ply sampled from the surfaces over the scene's time (each point
// with its time inside (0, 1)), and manifest.json (versions, preset, seed, render settings,
// dynamic range, SHA-256 of every file).
//
// Output of one scene, OUT/<scene>/ (with --val-every, transforms_val.json too):
//   hdr/camCC_tTTTT.exr            one linear render per camera and timestamp
//   images/camCC_tTTTT_eK.png      LDR at exposure index K (0.125, 2, 32 s)
//   transforms_train.json, transforms_test.json, point3d.ply, synthesis.json
//   render_plan.json               what Blender was asked to render (rerunnable by hand)
//   render_info.json               what Blender reports (version, camera matrices, markers)
//   manifest.json, blender.log
// The scene is built in OUT/<scene>.partial and moved into place only when complete, so a
// failed run keeps the previous dataset; the partial folder keeps blender.log for diagnosis.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/radiometry/exposure_stack.h"
#include "core/dataset/val_split.h"
#include "core/radiometry/ldr_synthesis.h"
#include "datagen/blender_render.h"
#include "datagen/dynamic_range.h"
#include "datagen/scene_presets.h"

namespace hdr4d::datagen {

struct DatagenOptions {
  std::string scene = "all";  // a scene name (AllScenes) or "all"
  std::string preset = "mini";
  std::filesystem::path out;
  std::uint64_t seed = 0;
  std::string blender;      // empty: $HDR4D_BLENDER, then blender on PATH
  std::string scripts_dir;  // empty: $HDR4D_DATAGEN_DIR, then the source tree's datagen/blender
  int threads = 0;          // Cycles threads; 0 = every core (the pixels do not depend on it)
  int samples = 0;          // Cycles samples per pixel; 0 = the preset's
  int width = 0;            // image width; 0 = the preset's (the height follows the aspect)
  int points = 0;           // point3d.ply size; 0 = the preset's (not with --capture)
  // --reuse-renders DIR: take each scene's renders from DIR/<scene> when datagen made it from
  // the same render plan (ReuseRenders), so another camera pipeline of a scene costs no Blender
  // time; otherwise render, saying why. Not with --capture.
  std::filesystem::path reuse_renders;
  // --val-every K: every frame of one training time in K (the middle of each run of K) goes to
  // transforms_val.json, so that `hdr4d train`'s default stops once those views stop improving
  // (core/dataset/val_split.h). 0: the paper's train / test splits only. Unset: ValEveryFor's
  // choice. Set to anything but 0, not with --capture.
  std::optional<int> val_every;
  // The K a scene gets: val_every where set; else kMonocularValEvery for one moving camera with
  // at least kMinTimesForMonocularVal training times (mini and paper presets), 0 otherwise (rigs,
  // whose held-back time or camera costs more than the stop saves, and the ci preset).
  int ValEveryFor(const ScenePreset& preset) const;
  // LDR synthesis, as the demo and HDR-4D-Syn-style data: a camera response, shot and read
  // noise, 8 bits. The noise seed is the scene seed. Unset: the scene's defaults (a filmic
  // response with full well 20000 and read noise 0.002; `studio` has its own, see SceneInfo).
  std::optional<std::string> crf;
  std::optional<double> full_well;
  std::optional<double> read_sigma;
  // The camera pipeline of the LDR images (core/radiometry/camera_pipeline.h); its seed is
  // the scene seed. Not with --capture, whose cameras have --unlike-cameras instead.
  CameraPipelineOptions pipeline;
  bool show_progress = true;
  // --capture: instead of a dataset, the capture layout `hdr4d calibrate` reads (a fixed rig
  // with bracketed exposures) plus truth/ (datagen/capture_generator.h). One scene at a time.
  bool capture = false;
  int cameras = 0;  // capture rig cameras, the last one held out; 0 = kCaptureCameras
  int frames = 0;   // capture timestamps; 0 = the preset's count for the scene
  int extra_views = 0;  // capture: hand-held views of the empty scene in static/extra/
  // Capture: the bracket exposure times in seconds, increasing; empty = the scene's (0.125, 2,
  // 32 s: four stops apart, more than a camera's auto-bracketing gives).
  std::vector<double> brackets;
  // How the capture's cameras differ: none, gains (a gain per camera and colour channel, as
  // unlike sensors and white balance give), responses (each camera's response bent by its own
  // exponent, x^e with e in [0.9, 1.1]) or both. Camera 0 is always the reference.
  std::string unlike_cameras = "none";
  // Capture: the image height with --size WxH (0 = the width times the scene's aspect).
  int height = 0;
  // Capture: N exposure times one stop apart, centred on 2 s (--dense-brackets; 0 = --brackets
  // or the scene's).
  int dense_brackets = 0;
  // Capture: the sensor's black pedestal in 8-bit codes and the Gaussian noise around it in
  // codes (--black-level B[:SIGMA]); 0 = none, the LDR synthesis's own codes.
  double black_level = 0, black_noise = 0;
  // Capture: each camera's lens: none, distortion (its own radial k1, k2, pincushion), vignetting
  // (its own radial fall-off) or both (datagen/capture_lens.h).
  std::string lenses = "none";
  // Throws hdr4d::Error for an unknown scene or preset, an empty output folder, negative
  // threads, samples, width or points (or points above 10^7 or with --capture), a width above
  // kMaxImageSide, renders over kMaxRenderGiB (CheckRenderBudget), bad LDR
  // settings, capture flags without --capture, or a capture
  // of "all", of fewer than 2 or more than 12 cameras, fewer than 2 frames, more than 100
  // extra views, or brackets that are not at least two increasing positive times.
  void Validate() const;
  // The LDR synthesis of a scene: these options where set, else the scene's defaults.
  DatasetSynthesisOptions LdrFor(const std::string& scene) const;
  // The Blender run's settings, after finding Blender and the scripts folder: a missing one
  // fails here, before anything under --out is touched.
  BlenderSettings FoundBlender() const;
};

// The widest image datagen renders (--width, --size; every scene is at most as tall as wide): a
// float RGB frame of 8192x8192 is 0.8 GB, which Cycles' render buffers and datagen's per-frame
// passes hold a few times over.
inline constexpr int kMaxImageSide = 8192;
// The most one scene's renders may total as float RGB, 12 bytes a pixel before ZIP (which noisy
// renders barely shrink): 16 GiB, over six times the paper preset's largest scene (airplane, 350
// renders of 800x800: 2.5 GiB). Its 8-bit LDR views, which `hdr4d train` holds in memory, are
// then at most 12 GiB (three exposures a render), within a 24 GB machine.
inline constexpr double kMaxRenderGiB = 16;
// Throws hdr4d::Error naming the scene, the count and size of its renders, and the flags that
// shrink them, when `renders` of the preset's size pass kMaxRenderGiB.
void CheckRenderBudget(const ScenePreset& preset, std::size_t renders);

inline constexpr int kCaptureCameras = 6;
inline constexpr int kCaptureMaxCameras = 12;  // 30 degrees apart: 12 fill the circle
const std::vector<std::string>& UnlikeCamerasModes();  // none, gains, responses, both
const std::vector<std::string>& CaptureLensModes();    // none, distortion, vignetting, both

struct SceneResult {
  std::string scene;
  std::filesystem::path root;  // OUT/<scene>
  int renders = 0;
  int ldr_images = 0;
  bool capture = false;  // a capture (static/, sequence/, truth/) rather than a dataset
  int cameras = 0, frames = 0, brackets = 0, extra_views = 0;  // of a capture
  double blender_seconds = 0;  // Blender's wall time: start-up, scene building, every render
  std::filesystem::path renders_reused_from;  // --reuse-renders: the scene folder, when reused
  int val_frames = 0;     // --val-every: training frames moved to transforms_val.json
  std::string val_split;  // and which, in words (empty: no val split)
  double total_seconds = 0;
  DynamicRange range;
};

// Renders one scene (not "all") into options.out / scene. Throws hdr4d::Error naming the scene,
// the frame and the file for a missing Blender, a failing script (non-zero exit), a missing or
// corrupt EXR, an output folder that cannot be written or that holds something other than a
// previous datagen run.
SceneResult GenerateScene(const DatagenOptions& options, const std::string& scene);

// With options.capture: the capture of one scene (datagen/capture_generator.h).
// Every scene options.scene names ("all" = the eight HDR-4D-Syn-style scenes), in order;
// on_done (optional) hears of each scene as soon as it is finished.
std::vector<SceneResult> Generate(const DatagenOptions& options,
                                  const std::function<void(const SceneResult&)>& on_done = {});

}  // namespace hdr4d::datagen
