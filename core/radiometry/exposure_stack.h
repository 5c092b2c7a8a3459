// Dataset-level exposure work: synthesising every frame's LDR image from its HDR ground truth
// (the way HDR-4D-Syn-style data is made), and merging the frames that share a view and a time
// back into HDR with the known camera response (classic multi-exposure fusion).
#pragma once

#include <filesystem>
#include <string>

#include "core/dataset/dataset.h"
#include "core/radiometry/camera_pipeline.h"
#include "core/radiometry/crf.h"
#include "core/radiometry/ldr_synthesis.h"

namespace hdr4d {

struct DatasetSynthesisOptions {
  std::string crf = "filmic";  // ParseCrf spec
  SensorNoise noise;           // seed is mixed with each frame's split and index
  int bits = 8;
  bool overwrite = true;  // false: keep LDR images that already exist
  // Replace existing LDR images although the scene has no synthesis.json (synth-ldr did not make
  // them); without it such images are refused.
  bool replace_foreign = false;
  // A hidden in-camera gain that changes over time, as auto-exposure compensation or in-camera
  // tone adjustments do: frame at normalised time t is exposed at exposure x
  // exp(gain_drift (t - 0.5)) while its JSON keeps the nominal exposure. 0 = a fixed response.
  // The case a dynamic tone mapper exists for; merge-hdr assumes 0.
  double gain_drift = 0.0;
  // The camera pipeline (core/radiometry/camera_pipeline.h); the default, fixed, is the plain
  // response above. Recorded in synthesis.json under "pipeline" unless it is the identity.
  CameraPipelineOptions pipeline;
  ExposureUnit exposure_unit = ExposureUnit::kSeconds;  // how the scene's exposures are read
  void Validate() const;
};

// Reads the dataset at `root` (its LDR images need not exist yet), writes each frame's LDR image
// from its exr_file_path at the frame's exposure, and records the settings in
// <root>/synthesis.json. Returns the number of images written. Every frame needs an HDR image.
int SynthesizeDatasetLdr(const std::filesystem::path& root, const DatasetSynthesisOptions& options);

struct MergeOptions {
  std::string crf;  // empty: the one recorded in <root>/synthesis.json
  std::string split = "test";
  ExposureUnit exposure_unit = ExposureUnit::kSeconds;  // how the scene's exposures are read
  bool overwrite = false;  // replace merged images already in the output folder
  void Validate() const;
};

// Merges, for each HDR ground-truth file of the split, the LDR frames that reference it (one view
// at one time, several exposures) into <out>/<same file name>.exr. Returns the number written.
int MergeDatasetExposures(const std::filesystem::path& root,
                          const std::filesystem::path& out,
                          const MergeOptions& options);

}  // namespace hdr4d
