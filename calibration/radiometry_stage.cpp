#include "calibration/radiometry_stage.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "calibration/camera_gains.h"
#include "calibration/hdr_fusion.h"
#include "calibration/undistort.h"
#include "calibration/vignetting_correction.h"
#include "core/image/image_io.h"
#include "core/util/error.h"
#include "core/util/progress.h"

namespace hdr4d {
namespace fs = std::filesystem;

namespace {

// Above this spread the cameras get their own curves (a few percent is recovery noise).
constexpr double kDifferentResponses = 0.05;

Bracket LoadBracket(const fs::path& path, double exposure, const std::string& camera, int frame) {
  if (IsHdrPath(path))
    Fail("{}: camera {}, frame {}: EXR brackets are not supported yet (use JPEG, PNG or TIFF)",
         path.string(), camera, frame);
  Bracket b;
  b.image = ReadImage(path);
  if (b.image.channels() < 3)
    Fail("{}: camera {}, frame {}: {} channel(s); calibrate needs colour images", path.string(),
         camera, frame, b.image.channels());
  if (b.image.channels() > 3) b.image = b.image.Rgb();
  b.exposure = exposure;
  b.name = path.string();
  return b;
}

// Codes clear of the black floor and of saturation (as the static images' gains use them).
constexpr int kMeasuredLowCode = 16, kMeasuredHighCode = 240;

// A frame whose brackets are all black or all saturated measures no radiance: its fusion gave
// "dynamic range 0.00 stops" and a response fitted to nothing. At least 0.1% of its values must
// lie between the black floor and saturation in some bracket.
void RequireMeasurement(const std::vector<Bracket>& brackets, const std::string& camera,
                        int frame) {
  std::size_t measured = 0, values = 0;
  for (const Bracket& b : brackets) {
    values += b.image.size();
    for (std::size_t i = 0; i < b.image.size(); ++i) {
      const int code = CodeOf(b.image.data()[i]);
      measured += code >= kMeasuredLowCode && code <= kMeasuredHighCode;
    }
  }
  if (measured == 0 || measured * 1000 < values)
    Fail("{}: camera {}, frame {}: no usable measurement in its {} brackets ({} of {} values "
         "between codes {} and {}; the rest black or saturated): check the exposure times and "
         "the lens cap", brackets.front().name, camera, frame, brackets.size(), measured, values,
         kMeasuredLowCode, kMeasuredHighCode);
}

// The mean code of a bracket: it cannot fall as the exposure grows (saturation only holds it).
double MeanCode(const Bracket& b) {
  double sum = 0;
  for (float v : b.image.values()) sum += CodeOf(v);
  return sum / static_cast<double>(std::max<std::size_t>(1, b.image.size()));
}

// Exposure times given in another order than the files (exposures.json's `brackets` lists them
// by bracket index: [32, 2, 0.125] for files darkest first) would fit the response to the wrong
// times without a word: the longest exposure's bracket must not be darker than the shortest's.
void RequireBrighterWithExposure(const std::vector<Bracket>& brackets, const std::string& camera,
                                 int frame) {
  const auto [shortest, longest] = std::minmax_element(
      brackets.begin(), brackets.end(),
      [](const Bracket& a, const Bracket& b) { return a.exposure < b.exposure; });
  const double dark = MeanCode(*shortest), bright = MeanCode(*longest);
  if (bright + 1.0 < dark)
    Fail("{}: camera {}, frame {}: at {} s its mean code is {:.1f}, darker than {:.1f} at {} s in "
         "{}: the exposure times do not follow the brackets (check the order of exposures.json's "
         "\"brackets\": bracket k's time is entry k)",
         longest->name, camera, frame, longest->exposure, bright, dark, shortest->exposure,
         shortest->name);
}

std::vector<Bracket> LoadFrame(const CaptureCamera& camera, const CaptureFrame& frame) {
  std::vector<Bracket> brackets;
  for (std::size_t k = 0; k < frame.brackets.size(); ++k)
    brackets.push_back(LoadBracket(frame.brackets[k], frame.exposures[k], camera.name, frame.index));
  RequireMeasurement(brackets, camera.name, frame.index);
  RequireBrighterWithExposure(brackets, camera.name, frame.index);
  return brackets;
}

// One response per camera (in capture order): the rig's joint curve, or each camera's own.
std::vector<CameraResponse> ChooseResponses(const Capture& capture, const std::vector<std::vector<Bracket>>& stacks,
                                            const CalibrateOptions& options, const fs::path& staging,
                                            CalibrationRecord* record) {
  const CameraResponse joint = RecoverResponse(stacks, options.response);
  WriteResponseCsv((staging / "response.csv").string(), joint);
  WriteResponsePlot((staging / "response.png").string(), joint);
  record->response_method = joint.method;
  std::vector<CameraResponse> own;
  if (stacks.size() >= 2) {
    for (const auto& stack : stacks) own.push_back(RecoverResponse({stack}, options.response));
    record->response_spread = ResponseSpread(own);
  }
  record->per_camera_response =
      !own.empty() && (options.per_camera_response || record->response_spread > kDifferentResponses);
  if (!record->per_camera_response) return std::vector<CameraResponse>(capture.cameras.size(), joint);
  for (std::size_t c = 0; c < own.size(); ++c) {
    const std::string name = capture.cameras[c].name;
    WriteResponseCsv((staging / fmt::format("response_{}.csv", name)).string(), own[c]);
    WriteResponsePlot((staging / fmt::format("response_{}.png", name)).string(), own[c]);
  }
  return own;
}

// Codes of a static image clear of the black floor and of saturation, linearised for the gains.
constexpr int kStaticLowCode = 16, kStaticHighCode = 240;

// The camera's first static image (the empty scene the sparse points come from) through its
// response, in the units of its first frame's fused HDR: scaled by the median ratio over the
// pixels where both are measured (same camera, same pixel: only the static image's exposure,
// which calibrate is not told, and whatever moved differ). NaN where a code is unusable. Empty
// without a static image or where its size differs from the frame's.
Image StaticRadiance(const CaptureCamera& camera, const CameraResponse& response, const Image& fused) {
  if (camera.static_images.empty()) return {};
  const fs::path& path = camera.static_images.front();
  if (IsHdrPath(path)) return {};
  Image image = ReadImage(path);
  if (image.channels() < 3 || image.width() != fused.width() || image.height() != fused.height()) return {};
  image = image.Rgb();
  std::array<std::vector<double>, 3> ratios;
  for (std::size_t i = 0; i < image.size(); ++i) {
    const int ch = static_cast<int>(i % 3), code = CodeOf(image.data()[i]);
    const double x = response.Linearize(ch, image.data()[i]);
    const bool usable = code >= kStaticLowCode && code <= kStaticHighCode && x > 0 && std::isfinite(x);
    image.data()[i] = usable ? static_cast<float>(x) : std::nanf("");
    const double f = fused.data()[i];
    if (usable && f > 0 && std::isfinite(f)) ratios[ch].push_back(f / x);
  }
  for (int ch = 0; ch < 3; ++ch) {
    if (ratios[ch].size() < 100) return {};
    auto mid = ratios[ch].begin() + ratios[ch].size() / 2;
    std::nth_element(ratios[ch].begin(), mid, ratios[ch].end());
    for (std::size_t i = ch; i < image.size(); i += 3) image.data()[i] *= static_cast<float>(*mid);
  }
  image.set_encoding(Encoding::kLinear);
  return image;
}

// Unlike cameras: gains on the points the cameras share, sampled in their static images (the
// empty scene) brought to the first frame's HDR units; the first frame itself where a camera has
// no usable static image. Measured on datagen's room (truth renders, no gains): the first
// frame's actors, seen differently by each camera, biased the gains by up to 2.7% and doubled
// the points' scatter (6.3% against 3.4% on the static renders).
std::optional<CameraGains> EstimateGains(const Capture& capture, const std::optional<Rig>& rig,
                                         const std::vector<std::vector<Bracket>>& stacks,
                                         const std::vector<CameraResponse>& responses,
                                         const CalibrateOptions& options) {
  if (!rig || rig->visibility.empty() || capture.cameras.size() < 2) return std::nullopt;
  std::vector<Image> fused, statics;  // the rig's camera order
  for (const RigCamera& rc : rig->cameras)
    for (std::size_t c = 0; c < capture.cameras.size(); ++c)
      if (capture.cameras[c].name == rc.name) {
        fused.push_back(FuseBrackets(stacks[c], responses[c], options.fusion).hdr);
        statics.push_back(StaticRadiance(capture.cameras[c], responses[c], fused.back()));
      }
  if (fused.size() != rig->cameras.size()) return std::nullopt;
  const bool use_static = std::none_of(statics.begin(), statics.end(), [](const Image& i) { return i.empty(); });
  CameraGains gains =
      EstimateCameraGains(*rig, use_static ? statics : fused, options.gain_footprint_pixels, options.vignetting);
  gains.from_static_images = use_static;
  return gains;
}

std::array<double, 3> GainOf(const CalibrationRecord& record, const std::optional<Rig>& rig, const std::string& name) {
  if (!record.gains || !record.gains_applied) return {1.0, 1.0, 1.0};
  for (std::size_t c = 0; c < rig->cameras.size(); ++c)
    if (rig->cameras[c].name == name) return record.gains->gain[c];
  return {1.0, 1.0, 1.0};
}

// The falloff divided out of a camera's HDR and brackets (0: none; camera_gains.h).
double VignettingOf(const CalibrationRecord& record, const std::optional<Rig>& rig, const std::string& name) {
  if (!record.gains) return 0;
  const std::vector<double>& applied = record.gains->vignetting_applied;
  for (std::size_t c = 0; c < rig->cameras.size() && c < applied.size(); ++c)
    if (rig->cameras[c].name == name) return applied[c];
  return 0;
}

// What one camera's frames share while they are written.
struct CameraOutput {
  const CaptureCamera& camera;
  int camera_id;
  const RigCamera* rig_camera;  // null without a rig
  const CameraResponse& response;
  std::array<double, 3> gain;
  double vignetting = 0;  // the falloff divided out of its HDR and brackets (rig cameras only)
};

// Copies (or, devignetted, undistorted or not 8-bit-friendly, re-encodes) bracket k into images/.
std::string WriteBracketImage(const CameraOutput& cam, const CaptureFrame& capture_frame, const Bracket& bracket,
                              std::size_t k, const fs::path& staging) {
  const fs::path& source = capture_frame.brackets[k];
  const bool undistort = cam.rig_camera && cam.rig_camera->undistort;
  std::string ext = source.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
  const bool devignette = cam.rig_camera && cam.vignetting != 0;
  const bool copy = !undistort && !devignette && (ext == ".png" || ext == ".jpg" || ext == ".jpeg");
  const std::string name =
      fmt::format("images/{}/{}{}", cam.camera.name, source.stem().string(), copy ? ext : ".png");
  fs::create_directories((staging / name).parent_path());
  if (copy) {
    fs::copy_file(source, staging / name, fs::copy_options::overwrite_existing);
  } else {
    Image ldr = devignette ? DevignetteDisplay(bracket.image, *cam.rig_camera, cam.vignetting, cam.response)
                           : bracket.image;
    if (undistort) ldr = Undistort(ldr, cam.rig_camera->intrinsics);
    WriteImage(staging / name, ldr, {.format = PixelFormat::kUint16});
  }
  return name;
}

Frame DatasetFrame(const CameraOutput& cam, const CaptureFrame& capture_frame, std::size_t k,
                   const std::string& image_name, const std::string& hdr_name, double fps) {
  const RigCamera& rc = *cam.rig_camera;
  Frame frame;
  frame.file_path = image_name;
  frame.exr_file_path = hdr_name;
  frame.time_raw = capture_frame.time ? *capture_frame.time : capture_frame.index / fps;
  // The camera's overall gain becomes part of its effective exposure, so that
  // LDR = response(radiance x exposure) holds for the corrected radiance.
  frame.exposure = capture_frame.exposures[k] * (cam.gain[0] + cam.gain[1] + cam.gain[2]) / 3;
  frame.exposure_given = true;
  frame.camera_id = cam.camera_id;
  frame.exposure_index = static_cast<int>(k);
  frame.camera.intrinsics = {rc.intrinsics.f, rc.intrinsics.f, rc.intrinsics.cx, rc.intrinsics.cy, rc.width, rc.height};
  frame.camera.world_from_cam_gl = rc.world_from_cam_gl;
  return frame;
}

// Fuses one frame, writes its HDR and its brackets, appends its dataset frames.
void WriteFrame(const CameraOutput& cam, const CaptureFrame& capture_frame, const CalibrateOptions& options,
                const fs::path& staging, CalibrationRecord* record, int* images_written, std::vector<Frame>* frames) {
  const std::vector<Bracket> brackets = LoadFrame(cam.camera, capture_frame);
  const Image& first = brackets.front().image;
  if (cam.rig_camera && (first.width() != cam.rig_camera->width || first.height() != cam.rig_camera->height))
    Fail("{}: camera {}, frame {}: size {}x{} differs from the static images' {}x{}", brackets.front().name,
         cam.camera.name, capture_frame.index, first.width(), first.height(), cam.rig_camera->width,
         cam.rig_camera->height);
  FusionResult fused = FuseBrackets(brackets, cam.response, options.fusion);
  for (std::size_t i = 0; i < fused.hdr.size(); ++i) fused.hdr.data()[i] /= static_cast<float>(cam.gain[i % 3]);
  // The falloff is in the image as captured: divided out before any undistortion.
  if (cam.rig_camera && cam.vignetting != 0) fused.hdr = DevignetteLinear(fused.hdr, *cam.rig_camera, cam.vignetting);
  if (cam.rig_camera && cam.rig_camera->undistort) fused.hdr = Undistort(fused.hdr, cam.rig_camera->intrinsics);
  const std::string hdr_name = fmt::format("hdr/{}/{:05d}.exr", cam.camera.name, capture_frame.index);
  WriteImage(staging / hdr_name, fused.hdr);
  ++*images_written;
  record->frames.push_back({cam.camera.name, capture_frame.index, fused.dynamic_range_stops,
                            fused.motion_fraction, fused.reference_bracket, fused.noise});
  for (std::size_t k = 0; k < brackets.size(); ++k) {
    const std::string name = WriteBracketImage(cam, capture_frame, brackets[k], k, staging);
    ++*images_written;
    if (cam.rig_camera) frames->push_back(DatasetFrame(cam, capture_frame, k, name, hdr_name, options.fps));
  }
}

}  // namespace

double ResponseSpread(const std::vector<CameraResponse>& responses) {
  double sum = 0;
  int count = 0;
  for (std::size_t a = 1; a < responses.size(); ++a)
    for (std::size_t c = 0; c < responses[a].inverse.size() && c < responses[0].inverse.size(); ++c)
      for (int z = 32; z < 224; ++z) {
        const double x0 = responses[0].inverse[c][z], x1 = responses[a].inverse[c][z];
        if (!(x0 > 0) || !(x1 > 0)) continue;
        sum += std::pow(std::log(x1 / x0), 2);
        ++count;
      }
  return count > 0 ? std::sqrt(sum / count) : 0.0;
}

std::vector<Frame> RunRadiometry(const Capture& capture, const CalibrateOptions& options,
                                 const std::optional<Rig>& rig, const fs::path& staging,
                                 CalibrationRecord* record, int* images_written) {
  std::vector<std::vector<Bracket>> stacks;
  for (const CaptureCamera& camera : capture.cameras) stacks.push_back(LoadFrame(camera, camera.frames.front()));
  const std::vector<CameraResponse> responses = ChooseResponses(capture, stacks, options, staging, record);
  record->gains = EstimateGains(capture, rig, stacks, responses, options);
  record->gains_applied = record->gains.has_value() && options.correct_gains;
  stacks.clear();

  std::size_t total = 0;
  for (const CaptureCamera& camera : capture.cameras) total += camera.frames.size();
  Progress progress("fuse", static_cast<std::int64_t>(total), options.show_progress);
  std::vector<Frame> frames;
  for (std::size_t c = 0; c < capture.cameras.size(); ++c) {
    const CaptureCamera& camera = capture.cameras[c];
    const RigCamera* rig_camera = rig ? rig->Find(camera.name) : nullptr;
    if (rig && !rig_camera)
      Fail("{}: camera {} is not in the rig of rig.json", (capture.root / "sequence" / camera.name).string(),
           camera.name);
    const CameraOutput cam{camera,       static_cast<int>(c),          rig_camera,
                           responses[c], GainOf(*record, rig, camera.name), VignettingOf(*record, rig, camera.name)};
    for (const CaptureFrame& capture_frame : camera.frames) {
      WriteFrame(cam, capture_frame, options, staging, record, images_written, &frames);
      progress.Advance(1, fmt::format("{} frame {}", camera.name, capture_frame.index));
    }
  }
  progress.Finish();
  return frames;
}

}  // namespace hdr4d
