// `hdr4d datagen --capture`: a scene rendered as a fixed rig would film it, written in the capture
// layout `hdr4d calibrate` reads (calibration/capture.h), with everything calibrate has to
// recover kept beside it as the truth it can be checked against.
//
// Output of one scene, OUT/<scene>/:
//   static/camCC/static.png         the empty scene (the scene's actors hidden, t = 0) at the
//                                   middle bracket's exposure: what COLMAP reconstructs
//   static/extra/extraNN.png        with --extra-views: hand-held views of the empty scene from
//                                   anywhere along the arc (a camera of the reference's make)
//   sequence/camCC/FFFFF_K.png      bracket K (exposure index into 0.125, 2, 32 s) of frame F
//   exposures.json                  {"brackets": [0.125, 2, 32]}
//   timestamps.json                 {"F": time} with the dataset's times (0 to 1)
//   truth/                          the original dataset of the same renders (ARCHITECTURE §3:
//                                   transforms_{train,test}.json with Blender's poses,
//                                   hdr/camCC_tFFFF.exr, images/, point3d.ply), the last camera
//                                   held out as calibrate holds it out, plus
//   truth/static/*.exr              the static renders
//   truth/cameras.json              per camera: intrinsics, camera-to-world (Blender/OpenGL
//                                   axes), gain per channel, response, the radiance range the
//                                   brackets measure, and the HDR file of every frame; the
//                                   extra views' poses
//   truth/response.csv              the reference camera's inverse response in calibrate's
//                                   format (code,r,g,b; x(128) = 1); response_camCC.csv for each
//                                   camera when their responses differ
//   manifest.json, render_plan.json, render_info.json, blender.log
// The rig: `cameras` on an arc 30 degrees apart around the scene, the last one lower and between
// two of them (the held-out view). With unlike cameras each camera c > 0 multiplies the radiance
// by its own gain per channel and/or bends the response to crf(x^e_c); camera 0 is the reference
// whose response and gains truth/ holds as the dataset's. Variants for calibrate to be tested on:
// --size WxH, --dense-brackets N (one stop apart), --black-level B[:SIGMA] (a pedestal with
// dark noise), --lenses (each camera's own radial distortion and/or vignetting,
// datagen/capture_lens.h); the bracket images go through them, truth/ keeps the pinhole renders
// and records every number (cameras.json: k1, k2, vignetting; noise: the pedestal).
#pragma once

#include <string>
#include <vector>

#include "datagen/generator.h"
#include "datagen/scene_presets.h"

namespace hdr4d::datagen {

// Renders and writes the capture of `scene` into options.out / scene (built in a .partial
// folder and moved into place when complete, as GenerateScene). Throws hdr4d::Error as
// GenerateScene does, naming the file.
SceneResult GenerateCapture(const DatagenOptions& options, const std::string& scene);

// The renders of a capture: every camera at every timestamp with every exposure, the last camera
// the test split, placed by the capture layout (datagen/blender/render_scene.py).
ScenePreset CapturePreset(const DatagenOptions& options, const std::string& scene);

// What Blender renders for it, relative to the capture folder: a static image per camera
// (truth/static/camCC.exr, `still`), the hand-held views (truth/static/extraNN.exr, camera ids
// after the rig's), then PlanRenders(preset) under truth/.
std::vector<PlannedRender> CaptureRenders(const ScenePreset& preset);

// The capture-only flag `options` sets that a dataset cannot take (--size, --dense-brackets,
// --black-level, --lenses), or nullptr.
const char* CaptureVariantFlag(const DatagenOptions& options);
// Throws hdr4d::Error for a capture variant out of range: --size (or the size --width gives)
// below 64x48 or above 8192,
// --dense-brackets outside 3..20 or with --brackets, a black level outside 0..64 codes or its
// noise outside 0..16, an unknown --lenses mode.
void ValidateCaptureVariant(const DatagenOptions& options);

// The file names of the layout, relative to the capture folder.
std::string CaptureCameraName(int camera);                      // camCC
std::string CaptureStaticFile(int camera);                      // static/camCC/static.png
std::string CaptureExtraName(int view);                         // extraNN
std::string CaptureExtraFile(int view);                         // static/extra/extraNN.png
std::string CaptureBracketFile(int camera, int frame, int k);  // sequence/camCC/FFFFF_K.png

}  // namespace hdr4d::datagen
