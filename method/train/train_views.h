// Training and test views held in memory: the camera, the normalised time and the LDR image in
// 8 bits per channel (a paper-size scene, 280 frames at 800x800, is then 0.5 GB, not 2 GB),
// converted to float one view at a time when it is used.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/camera.h"
#include "core/dataset/dataset.h"
#include "core/image/image_resize.h"  // DownsampleBox, ResolutionProblem
#include "method/train/hdr_training_options.h"

namespace hdr4d::method {

struct TrainView {
  Camera camera;
  float time = 0;
  int time_index = 0;   // radiance-bank row of `time` (set by the trainer)
  int image_index = 0;  // position in its split
  int camera_index = -1;  // its row of the per-camera correction (correction_cameras.h), if any
  double exposure = 1;
  std::string name;               // the image's file name (renders are written under it)
  std::vector<std::uint8_t> rgb;  // H x W x 3, display-encoded as stored; empty: not held
  // Where rgb comes from and how it is made (LoadViews): read again by ToFloat when not held.
  std::filesystem::path image_path;
  int resolution = 1;
  std::array<float, 3> background{};
  // HDR ground truth, when the frame has one: its file (renders are written under its name) and,
  // when loaded for training, the loss's target mu(gt / max) in 16 bits (quantisation 1.5e-5;
  // the maximum and mu as HdrTarget says).
  std::optional<std::filesystem::path> hdr_path;
  std::vector<std::uint16_t> hdr_mu;
  bool has_hdr() const { return hdr_path.has_value(); }
  int width() const { return camera.intrinsics.width; }
  int height() const { return camera.intrinsics.height; }
  // The image as floats in [0,1] (H x W x 3) into `out` (resized); read from image_path (and
  // checked again) when rgb is not held.
  void ToFloat(std::vector<float>* out) const;
  // The HDR target mu(gt / max gt) as floats (H x W x 3); requires loaded hdr_mu.
  void HdrMuToFloat(std::vector<float>* out) const;
};

// Reads the frames of `split`: RGB, or RGBA composited over `background` (the reference
// composites D-NeRF's RGBA onto black). Integer images are required (the LDR targets). With
// load_hdr, frames with an exr_file_path also get their mu-law HDR target (the file must be
// linear, the size of the LDR image, finite, with a positive maximum), encoded as `target` says.
// resolution R (>= 1, dividing every image's width and height; else hdr4d::Error naming the
// file): images reduced R times on load by an R x R box average (LDR in its stored encoding
// after compositing, HDR in linear radiance) and the intrinsics with them
// (PinholeIntrinsics::Downscaled).
std::vector<TrainView> LoadViews(const Dataset& dataset,
                                 Split split,
                                 const float background[3],
                                 bool load_hdr = false,
                                 int resolution = 1,
                                 HdrTarget target = HdrTarget::kImageMax);

// LoadViews without the HDR targets that keeps no pixels: every image is read and checked now
// (a bad file stops the run before it trains), and each view's ToFloat reads it again. For the
// test split, used once per evaluation: held, it is 345 MB of a paper-size scene at 800x800.
std::vector<TrainView> CheckViews(const Dataset& dataset,
                                  Split split,
                                  const float background[3],
                                  int resolution = 1);
// The median of log(HDR target) in the loss's units (hdr_mu decoded with `mu_law`) over a
// regular sample of the views' positive target values; nullopt when no view has an HDR target.
std::optional<float> MedianLogHdrTarget(const std::vector<TrainView>& views, double mu_law);

// The intrinsics of an image reduced by an integer `factor` (width and height divisible by it;
// checked). With pixel centres at i + 0.5 (core/geometry/camera.h, PIXEL CONVENTION) output pixel i
// covers input [i f, (i + 1) f), so every image coordinate, focal lengths and principal point
// included, is divided by f exactly.
PinholeIntrinsics DownscaledIntrinsics(const PinholeIntrinsics& intrinsics, int factor);

}  // namespace hdr4d::method
