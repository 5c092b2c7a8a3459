#include "datagen/capture_generator.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>

#include "core/radiometry/crf.h"
#include "core/dataset/dataset.h"
#include "core/util/error.h"
#include "core/image/image_io.h"
#include "core/files/json_util.h"
#include "core/radiometry/ldr_synthesis.h"
#include "datagen/blender_process.h"
#include "datagen/blender_render.h"
#include "datagen/capture_lens.h"
#include "datagen/dataset_assembly.h"
#include "datagen/output_folder.h"
#include "datagen/scene_presets.h"

namespace hdr4d::datagen {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kTruth = "truth";
// Codes whose exposure bounds the radiance the brackets measure: above the noise floor of the
// longest exposure, below the clip of the shortest.
constexpr double kLowCode = 8, kHighCode = 247;

std::uint64_t SplitMix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// The noise seed of one image of the capture: the scene seed, what the image is, camera, frame,
// bracket. `kind` 1 = a bracket, 2 = a static image.
std::uint64_t ImageSeed(std::uint64_t seed, int kind, int camera, int frame, int k) {
  std::uint64_t h = SplitMix(seed ^ 0x63617074757265ULL);  // "capture"
  for (const int v : {kind, camera, frame, k}) h = SplitMix(h ^ static_cast<std::uint64_t>(v + 1));
  return h;
}

// A camera whose response is the scene's bent by an exponent: y = crf(x^e). e = 1 is the
// scene's own response. Strictly increasing wherever the base is, saturating at x = s^(1/e).
class ExponentCrf final : public Crf {
 public:
  ExponentCrf(std::unique_ptr<Crf> base, double exponent)
      : base_(std::move(base)), e_(exponent) {}
  double Apply(double x) const override { return base_->Apply(std::pow(std::max(x, 0.0), e_)); }
  double Saturation() const override { return std::pow(base_->Saturation(), 1.0 / e_); }
  bool Invertible() const override { return base_->Invertible(); }
  double Inverse(double y) const override { return std::pow(base_->Inverse(y), 1.0 / e_); }
  std::string Spec() const override {
    return e_ == 1.0 ? base_->Spec() : fmt::format("{} of x^{:.6g}", base_->Spec(), e_);
  }
  json ToJson() const override {
    return {{"type", "exponent"}, {"exponent", e_}, {"base", base_->ToJson()}};
  }

 private:
  std::unique_ptr<Crf> base_;
  double e_;
};

struct RigCamera {
  std::string name;
  std::array<double, 3> gain = {1, 1, 1};
  double exponent = 1;
  std::unique_ptr<Crf> crf;
  CaptureLens lens;
};

// The sensor every camera of the capture shares beyond the LDR synthesis's noise.
struct Pedestal {
  double black = 0, noise = 0;  // 8-bit codes
};

// What every image of the capture goes through besides its camera's own response and gains.
struct CaptureSensor {
  SensorNoise noise;
  Pedestal pedestal;
  PinholeIntrinsics intrinsics;  // of every camera (one make, one field of view)
};

// Camera 0 is the reference; the others draw their gains (about 0.74 to 1.35 per channel) and
// response exponents (0.9 to 1.1) from the seed.
std::vector<RigCamera> MakeRigCameras(const DatagenOptions& options, const std::string& crf,
                                      int count) {
  const bool gains = options.unlike_cameras == "gains" || options.unlike_cameras == "both";
  const bool responses = options.unlike_cameras == "responses" || options.unlike_cameras == "both";
  std::mt19937_64 rng(SplitMix(options.seed ^ 0x756e6c696b65ULL));  // "unlike"
  std::uniform_real_distribution<double> log_gain(-0.3, 0.3), exponent(0.9, 1.1);
  const std::vector<CaptureLens> lenses = DrawCaptureLenses(options.lenses, options.seed, count);
  std::vector<RigCamera> cameras;
  for (int c = 0; c < count; ++c) {
    RigCamera camera;
    camera.name = CaptureCameraName(c);
    // Drawn for every camera whatever the mode, so that a camera's gains do not depend on it.
    std::array<double, 3> g;
    for (double& v : g) v = std::exp(log_gain(rng));
    const double e = exponent(rng);
    if (c > 0 && gains) camera.gain = g;
    if (c > 0 && responses) camera.exponent = e;
    camera.crf = std::make_unique<ExponentCrf>(ParseCrf(crf), camera.exponent);
    camera.lens = lenses[c];
    cameras.push_back(std::move(camera));
  }
  return cameras;
}

// The image a camera records of `hdr` (already through its lens): its gains on the radiance,
// then exposure, noise, its response, the pedestal and 8 bits.
Image Record(const Image& hdr, const RigCamera& camera, double exposure, const SensorNoise& noise,
             const Pedestal& pedestal, std::uint64_t seed) {
  Image scaled = hdr.Rgb();
  float* v = scaled.data();
  for (std::size_t i = 0; i < scaled.size(); ++i) v[i] *= static_cast<float>(camera.gain[i % 3]);
  LdrSynthesisOptions ldr;
  ldr.exposure = exposure;
  ldr.noise = noise;
  ldr.noise.seed = seed;
  if (pedestal.black == 0 && pedestal.noise == 0) {
    ldr.bits = 8;
    return SynthesizeLdr(scaled, *camera.crf, ldr);
  }
  ldr.bits = 0;  // quantised with the pedestal
  return ApplyBlackLevel(SynthesizeLdr(scaled, *camera.crf, ldr), pedestal.black, pedestal.noise,
                         SplitMix(seed ^ 0x626c61636bULL));  // "black"
}

// Calibrate's inverse-response format: code,r,g,b, exposure per code relative to code 128.
// Codes at or below the pedestal `black` are exposure 0.
void WriteResponseCsv(const fs::path& path, const Crf& crf, double black) {
  auto display = [&](double z) { return std::clamp((z - black) / (255.0 - black), 0.0, 1.0); };
  const double mid = crf.Inverse(display(128));
  std::string text =
      fmt::format("# inverse camera response (truth: {}): relative exposure per code, x(128) = 1\n"
                  "code,r,g,b\n",
                  crf.Spec());
  for (int z = 0; z < 256; ++z) {
    const double x = crf.Inverse(display(z)) / mid;
    text += fmt::format("{},{:.9g},{:.9g},{:.9g}\n", z, x, x, x);
  }
  WriteTextFileAtomic(path, text);
}

json MatrixJson(const Eigen::Matrix4d& m) {
  json rows = json::array();
  for (int r = 0; r < 4; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  return rows;
}

// --dense-brackets N: N times one stop apart, centred on 2 s.
std::vector<double> DenseBrackets(int n) {
  std::vector<double> times;
  for (int k = 0; k < n; ++k) times.push_back(2.0 * std::exp2(k - (n - 1) / 2.0));
  return times;
}

}  // namespace

const std::vector<std::string>& CaptureLensModes() {
  static const std::vector<std::string> modes = {"none", "distortion", "vignetting", "both"};
  return modes;
}

const char* CaptureVariantFlag(const DatagenOptions& o) {
  return o.height != 0                                  ? "--size"
         : o.dense_brackets != 0                        ? "--dense-brackets"
         : o.black_level != 0 || o.black_noise != 0     ? "--black-level"
         : o.lenses != "none"                           ? "--lenses"
                                                        : nullptr;
}

void ValidateCaptureVariant(const DatagenOptions& o) {
  if (o.height < 0 || (o.height > 0 && o.width <= 0))
    Fail("datagen: --size {}x{}: give both sides, positive", o.width, o.height);
  constexpr int kMax = kMaxImageSide;
  if (o.height > 0 && (o.width < 64 || o.height < 48 || o.width > kMax || o.height > kMax))
    Fail("datagen: --size {}x{}: use 64x48 to 8192x8192", o.width, o.height);
  // --width alone: the same bounds on the size it gives (the height from the scene's aspect).
  if (o.height == 0 && o.width > 0) {
    const ScenePreset p = ResolvePreset(o.scene, o.preset, o.width);
    if (p.width < 64 || p.height < 48 || p.width > kMax || p.height > kMax)
      Fail("datagen: --width {} gives {}x{} capture images (the scene's aspect): use 64x48 to "
           "8192x8192, as --size", o.width, p.width, p.height);
  }
  if (o.dense_brackets != 0 && (o.dense_brackets < 3 || o.dense_brackets > 20))
    Fail("datagen: --dense-brackets {}: use 3 to 20 brackets (one stop apart)", o.dense_brackets);
  if (o.dense_brackets != 0 && !o.brackets.empty())
    Fail("datagen: --dense-brackets and --brackets both give the exposure times; give one");
  if (!(o.black_level >= 0 && o.black_level <= 64))
    Fail("datagen: --black-level {}: use 0 to 64 codes", o.black_level);
  if (!(o.black_noise >= 0 && o.black_noise <= 16))
    Fail("datagen: --black-level noise {}: use 0 to 16 codes", o.black_noise);
  if (std::find(CaptureLensModes().begin(), CaptureLensModes().end(), o.lenses) == CaptureLensModes().end())
    Fail("datagen: --lenses {}: use none, distortion, vignetting or both", o.lenses);
}

ScenePreset CapturePreset(const DatagenOptions& options, const std::string& scene) {
  ScenePreset preset = ResolvePreset(scene, options.preset, options.width);
  if (options.samples > 0) preset.samples = options.samples;
  const int timestamps = preset.timestamps();
  preset.rig = Rig::kMultiView;
  preset.exposure_pattern = ExposurePattern::kEveryExposure;
  preset.cameras = options.cameras > 0 ? options.cameras : kCaptureCameras;
  preset.held_out_cameras = 1;
  preset.train_timestamps = options.frames > 0 ? options.frames : std::max(2, timestamps);
  preset.test_timestamps = 0;
  preset.layout = "capture";
  preset.extra_views = options.extra_views;
  if (options.height > 0) preset.height = options.height;  // --size WxH
  if (!options.brackets.empty()) preset.exposures = options.brackets;
  if (options.dense_brackets > 0) preset.exposures = DenseBrackets(options.dense_brackets);
  return preset;
}

std::vector<PlannedRender> CaptureRenders(const ScenePreset& preset) {
  std::vector<PlannedRender> renders;
  for (int c = 0; c < preset.cameras; ++c) {
    PlannedRender r;
    r.hdr_file = fmt::format("{}/static/{}.exr", kTruth, CaptureCameraName(c));
    r.camera_id = c;
    r.still = true;
    renders.push_back(r);
  }
  for (int j = 0; j < preset.extra_views; ++j) {
    PlannedRender r;
    r.hdr_file = fmt::format("{}/static/{}.exr", kTruth, CaptureExtraName(j));
    r.camera_id = preset.cameras + j;
    r.still = true;
    renders.push_back(r);
  }
  for (PlannedRender r : PlanRenders(preset)) {
    r.hdr_file = fmt::format("{}/{}", kTruth, r.hdr_file);
    renders.push_back(std::move(r));
  }
  return renders;
}

std::string CaptureCameraName(int camera) { return fmt::format("cam{:02d}", camera); }

std::string CaptureExtraName(int view) { return fmt::format("extra{:02d}", view); }

std::string CaptureExtraFile(int view) {
  return fmt::format("static/extra/{}.png", CaptureExtraName(view));
}

std::string CaptureStaticFile(int camera) {
  return fmt::format("static/{}/static.png", CaptureCameraName(camera));
}

std::string CaptureBracketFile(int camera, int frame, int k) {
  return fmt::format("sequence/{}/{:05d}_{}.png", CaptureCameraName(camera), frame, k);
}

namespace {

// truth/: the original dataset of the sequence renders, its point cloud and LDR images.
struct TruthDataset {
  Dataset dataset;
  std::int64_t points = 0;
  int ldr_images = 0;
};

TruthDataset WriteTruthDataset(const ScenePreset& preset, const std::vector<PlannedRender>& sequence,
                               const std::vector<PlannedRender>& renders, const BlenderRender& run,
                               const DatasetSynthesisOptions& ldr, const fs::path& staging) {
  const fs::path truth = staging / kTruth;
  json sequence_info = run.info;
  sequence_info["renders"] = json::array();
  const int stills = preset.cameras + preset.extra_views;  // CaptureRenders puts them first
  for (std::size_t i = stills; i < renders.size(); ++i)
    sequence_info["renders"].push_back(run.info["renders"][i]);
  TruthDataset out;
  out.dataset = BuildDataset(preset, sequence, sequence_info, truth);
  WriteDataset(out.dataset, truth);
  std::error_code ec;
  fs::rename(staging / kPointsFile, truth / kPointsFile, ec);
  if (ec) {
    Fail("datagen: scene '{}': {}: cannot move the surface points into {} ({})", preset.scene,
         (staging / kPointsFile).string(), truth.string(), ec.message());
  }
  out.points = WritePointCloud(preset, sequence_info, truth);
  out.ldr_images = SynthesizeDatasetLdr(truth, ldr);
  const DatasetReport report = CheckDataset(truth, {.image_check = ImageCheck::kFull});
  if (!report.ok()) {
    Fail("datagen: scene '{}': the truth dataset {} fails `hdr4d dataset check`: {}",
         preset.scene, truth.string(), report.problems.front().ToString());
  }
  return out;
}

// The static images (rig cameras, then hand-held extra views); returns the extra views' truth.
json WriteStillImages(const DatagenOptions& options, const ScenePreset& preset,
                      const std::vector<PlannedRender>& renders, const BlenderRender& run,
                      const std::vector<RigCamera>& cameras, const CaptureSensor& sensor,
                      const fs::path& staging, int* images) {
  const int middle = static_cast<int>(preset.exposures.size()) / 2;
  json extra_views = json::array();
  for (int i = 0; i < preset.cameras + preset.extra_views; ++i) {
    const bool extra = i >= preset.cameras;
    const int j = i - preset.cameras;
    // A hand-held camera is of the reference's make, its lens too.
    const RigCamera& camera = cameras[extra ? 0 : i];
    const Image hdr = ApplyCaptureLens(ReadImage(staging / renders[i].hdr_file), camera.lens, sensor.intrinsics);
    WriteImage(staging / (extra ? CaptureExtraFile(j) : CaptureStaticFile(i)),
               Record(hdr, camera, preset.exposures[middle], sensor.noise, sensor.pedestal,
                      extra ? ImageSeed(options.seed, 3, j, 0, middle) : ImageSeed(options.seed, 2, i, 0, middle)),
               {.format = PixelFormat::kUint8});
    if (extra)
      extra_views.push_back({{"name", CaptureExtraName(j)},
                             {"file", CaptureExtraFile(j)},
                             {"static_hdr", fmt::format("static/{}.exr", CaptureExtraName(j))},
                             {"transform_matrix", run.info["renders"][i]["transform_matrix"]}});
    ++*images;
  }
  return extra_views;
}

void WriteBrackets(const DatagenOptions& options, const ScenePreset& preset,
                   const std::vector<PlannedRender>& sequence, const std::vector<RigCamera>& cameras,
                   const CaptureSensor& sensor, const fs::path& staging, int* images) {
  const fs::path truth = staging / kTruth;
  const bool alike = options.unlike_cameras == "none" && options.lenses == "none" &&
                     sensor.pedestal.black == 0 && sensor.pedestal.noise == 0;
  for (const PlannedRender& r : sequence) {
    const RigCamera& camera = cameras[r.camera_id];
    const Image hdr = alike ? Image()
                            : ApplyCaptureLens(ReadImage(truth / r.hdr_file), camera.lens, sensor.intrinsics);
    for (int k : r.exposure_indices) {
      const fs::path target = staging / CaptureBracketFile(r.camera_id, r.time_index, k);
      if (alike) {
        // Alike cameras record exactly the dataset's LDR images.
        fs::create_directories(target.parent_path());
        fs::copy_file(truth / LdrFileName(r, k), target, fs::copy_options::overwrite_existing);
      } else {
        WriteImage(target,
                   Record(hdr, camera, preset.exposures[k], sensor.noise, sensor.pedestal,
                          ImageSeed(options.seed, 1, r.camera_id, r.time_index, k)),
                   {.format = PixelFormat::kUint8});
      }
      ++*images;
    }
  }
  WriteJsonFile(staging / "exposures.json", {{"brackets", preset.exposures}});
  json timestamps = json::object();
  for (const PlannedRender& r : sequence) timestamps[std::to_string(r.time_index)] = r.time;
  WriteJsonFile(staging / "timestamps.json", timestamps);
}

json TruthCamera(const ScenePreset& preset, const std::vector<PlannedRender>& sequence, const Dataset& dataset,
                 const RigCamera& camera, const Pedestal& pedestal, int c) {
  const double t_min = *std::min_element(preset.exposures.begin(), preset.exposures.end());
  const double t_max = *std::max_element(preset.exposures.begin(), preset.exposures.end());
  const Frame* first = nullptr;
  for (const Frame* f : dataset.AllFrames())
    if (f->camera_id == c && first == nullptr) first = f;
  HDR4D_CHECK(first != nullptr);
  json hdr_files = json::object();  // frame number -> HDR file, relative to truth/
  for (const PlannedRender& r : sequence)
    if (r.camera_id == c) hdr_files[std::to_string(r.time_index)] = r.hdr_file;
  const PinholeIntrinsics& k = first->camera.intrinsics;
  // Above the pedestal: the low code clears its noise (three widths) as well.
  const double span = 255.0 - pedestal.black;
  const double y_low = std::max(kLowCode, 3 * pedestal.noise) / span;
  const double y_high = std::clamp((kHighCode - pedestal.black) / span, y_low, 1.0);
  json low = json::array(), high = json::array();
  for (int ch = 0; ch < 3; ++ch) {
    low.push_back(camera.crf->Inverse(y_low) / (t_max * camera.gain[ch]));
    high.push_back(camera.crf->Inverse(y_high) / (t_min * camera.gain[ch]));
  }
  return {{"name", camera.name},
          {"camera_id", c},
          {"held_out", c == preset.cameras - 1},
          {"width", k.width},
          {"height", k.height},
          {"fx", k.fx},
          {"fy", k.fy},
          {"cx", k.cx},
          {"cy", k.cy},
          {"k1", camera.lens.k1},
          {"k2", camera.lens.k2},
          {"vignetting", camera.lens.vignetting},
          {"transform_matrix", MatrixJson(first->camera.world_from_cam_gl)},
          {"gain", camera.gain},
          {"response_exponent", camera.exponent},
          {"crf", camera.crf->ToJson()},
          {"crf_spec", camera.crf->Spec()},
          {"measured_radiance",
           {{"low", low},
            {"high", high},
            {"note", fmt::format("radiance whose code is {} above the pedestal (or 3 noise widths) at "
                                 "the longest and {} at the shortest exposure; at the image centre "
                                 "(vignetting darkens the corners)",
                                 kLowCode, kHighCode)}}},
          {"static_hdr", fmt::format("static/{}.exr", camera.name)},
          {"hdr_files", hdr_files}};
}

// truth/cameras.json and the responses.
void WriteTruthCameras(const DatagenOptions& options, const ScenePreset& preset,
                       const std::vector<PlannedRender>& sequence, const Dataset& dataset,
                       const std::vector<RigCamera>& cameras, const CaptureSensor& sensor, json extra_views,
                       const fs::path& truth) {
  json truth_cameras = json::array();
  for (int c = 0; c < preset.cameras; ++c)
    truth_cameras.push_back(TruthCamera(preset, sequence, dataset, cameras[c], sensor.pedestal, c));
  const int middle = static_cast<int>(preset.exposures.size()) / 2;
  WriteJsonFile(truth / "cameras.json",
                {{"format", "hdr4d-capture-truth"},
                 {"format_version", 1},
                 {"scene", preset.scene},
                 {"axes", "transform_matrix: camera-to-world, Blender/OpenGL axes (the dataset's)"},
                 {"exposures", preset.exposures},
                 {"static_exposure", preset.exposures[middle]},
                 {"unlike_cameras", options.unlike_cameras},
                 {"lenses", options.lenses},
                 {"noise",
                  {{"full_well", sensor.noise.full_well},
                   {"read_sigma", sensor.noise.read_sigma},
                   {"black_level_codes", sensor.pedestal.black},
                   {"black_noise_codes", sensor.pedestal.noise}}},
                 {"cameras", truth_cameras},
                 {"extra_views", std::move(extra_views)}});
  WriteResponseCsv(truth / "response.csv", *cameras[0].crf, sensor.pedestal.black);
  if (options.unlike_cameras == "responses" || options.unlike_cameras == "both") {
    for (const RigCamera& camera : cameras)
      WriteResponseCsv(truth / fmt::format("response_{}.csv", camera.name), *camera.crf,
                       sensor.pedestal.black);
  }
}

json CaptureManifest(const DatagenOptions& options, const ScenePreset& preset, const BlenderRender& run,
                     const SceneResult& result, const TruthDataset& truth, const DatasetSynthesisOptions& ldr) {
  const SceneInfo& scene_info = FindScene(preset.scene);
  return {
      {"generator", kGenerator},
      {"generator_version",
       fmt::format("hdr4d {}, datagen format {}, scripts {}", HDR4D_DATAGEN_VERSION,
                   kPlanFormatVersion, run.info.value("script_version", 0))},
      {"mode", "capture"},
      {"scene", preset.scene},
      {"description", scene_info.description},
      {"preset", preset.preset},
      {"seed", options.seed},
      {"blender_version", run.info["blender_version"]},
      {"render",
       {{"engine", "CYCLES"},
        {"device", "CPU"},
        {"samples", preset.samples},
        {"width", preset.width},
        {"height", preset.height},
        {"threads", options.threads}}},
      {"capture",
       {{"cameras", preset.cameras},
        {"held_out_camera", CaptureCameraName(preset.cameras - 1)},
        {"layout", "an arc of neighbours 30 degrees apart at three heights; the held-out camera "
                   "lower, between two of them"},
        {"frames", preset.timestamps()},
        {"extra_views", preset.extra_views},
        {"brackets", preset.exposures},
        {"static_images", "the scene at t = 0 without its actors, at the middle bracket"},
        {"unlike_cameras", options.unlike_cameras},
        {"lenses", options.lenses},
        {"black_level_codes", options.black_level},
        {"black_noise_codes", options.black_noise}}},
      {"truth_dataset", {{"frames", truth.dataset.NumFrames()}, {"ldr_images", truth.ldr_images}}},
      {"ldr_synthesis",
       {{"crf_spec", ldr.crf},
        {"full_well", ldr.noise.full_well},
        {"read_sigma", ldr.noise.read_sigma},
        {"bits", 8}}},
      {"dynamic_range",
       {{"p0.1", result.range.p001},
        {"p99.9", result.range.p999},
        {"ratio_p99.9_p0.1", result.range.ratio}}},
      {"points", truth.points},
  };
}

}  // namespace

SceneResult GenerateCapture(const DatagenOptions& options, const std::string& scene) {
  options.Validate();
  if (!options.capture) Fail("datagen: GenerateCapture without --capture");
  const auto start = std::chrono::steady_clock::now();
  const ScenePreset preset = CapturePreset(options, scene);
  // The dataset's renders (names relative to truth/) and what Blender renders.
  const std::vector<PlannedRender> sequence = PlanRenders(preset);
  const std::vector<PlannedRender> renders = CaptureRenders(preset);

  const fs::path final_dir = options.out / preset.scene;
  const BlenderSettings blender = options.FoundBlender();
  const fs::path staging = PrepareStaging(final_dir, preset.scene);
  const BlenderRender run = RenderWithBlender(preset, renders, blender, staging);
  const LuminanceHistogram histogram = NormaliseExrs(preset, renders, staging);
  const DatasetSynthesisOptions ldr = options.LdrFor(preset.scene);
  const TruthDataset truth = WriteTruthDataset(preset, sequence, renders, run, ldr, staging);

  // The capture: what each camera records.
  const std::vector<RigCamera> cameras = MakeRigCameras(options, ldr.crf, preset.cameras);
  const CaptureSensor sensor{
      .noise = ldr.noise,
      .pedestal = {.black = options.black_level, .noise = options.black_noise},
      .intrinsics = truth.dataset.AllFrames().front()->camera.intrinsics};
  int images = 0;
  json extra_views = WriteStillImages(options, preset, renders, run, cameras, sensor, staging, &images);
  WriteBrackets(options, preset, sequence, cameras, sensor, staging, &images);
  WriteTruthCameras(options, preset, sequence, truth.dataset, cameras, sensor, std::move(extra_views),
                    staging / kTruth);

  SceneResult result;
  result.scene = preset.scene;
  result.root = final_dir;
  result.renders = static_cast<int>(renders.size());
  result.ldr_images = images;
  result.capture = true;
  result.cameras = preset.cameras;
  result.frames = preset.timestamps();
  result.brackets = static_cast<int>(preset.exposures.size());
  result.extra_views = preset.extra_views;
  result.blender_seconds = run.seconds;
  result.range = histogram.Summary();
  json manifest = CaptureManifest(options, preset, run, result, truth, ldr);
  result.total_seconds =
      FinishOutput(std::move(manifest), result.blender_seconds, result.renders, start, staging,
                   final_dir);
  return result;
}

}  // namespace hdr4d::datagen
