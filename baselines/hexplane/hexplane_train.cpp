#include "baselines/hexplane/hexplane_train.h"
#include "baselines/hexplane/heap_policy.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <random>
#include <sstream>

#include "baselines/hexplane/hexplane_adam.h"
#include "baselines/hexplane/hexplane_render.h"
#include "baselines/hexplane/ray_batch.h"
#include "baselines/hexplane/hexplane_train_state.h"
#include "baselines/hexplane/scene_bounds.h"
#include "core/dataset/dataset.h"
#include "core/files/json_util.h"
#include "core/files/output_guard.h"
#include "core/image/image_io.h"
#include "core/util/error.h"
#include "core/util/parallel.h"
#include "core/util/progress.h"

namespace hdr4d::baselines::hexplane {
namespace {

using method::TrainView;

// The HDR loss compares mu-law images of radiance over the ground truth's maximum per image
// (the mu-law target of the Gaussian trainer, method/train/train_views.h, mu 5000).
constexpr float kMu = 5000.0f;

float MuLaw(float x) { return std::log1p(kMu * std::max(x, 0.0f)) / std::log1p(kMu); }
float MuLawSlope(float x) { return x < 0 ? 0.0f : kMu / ((1 + kMu * x) * std::log1p(kMu)); }

class HexPlaneTraining {
 public:
  explicit HexPlaneTraining(HexPlaneTrainOptions o) : o_(std::move(o)) {}
  HexPlaneTrainSummary Run();

 private:
  void ReadRunToResume();
  void CheckResumedConfig() const;
  void SetUp();
  void Restore();
  nlohmann::json RunConfig() const;
  nlohmann::json CurveJson() const;
  void SaveCheckpoint(int iterations_done, double seconds) const;
  void FillPixelOrder();
  void NewEpoch(std::uint64_t seed);
  void MakeBatch(std::mt19937_64* rng);
  double LossGradient(const std::vector<float>& out, std::vector<float>* dout);
  void Regularise(float lr_factor);
  void Step(int it, std::mt19937_64* rng);
  void Schedules(int it);
  HexPlaneTrainSummary Finish(int iterations, double seconds);

  HexPlaneTrainOptions o_;
  HexPlaneConfig c_;
  Dataset dataset_;
  std::vector<TrainView> train_, test_;
  std::vector<float> hdr_max_;  // per training view, for the HDR loss
  HexPlaneModel model_;
  std::optional<PlainAdam> adam_;
  std::optional<HexPlaneGrads> grads_;
  RayBatch batch_;
  std::vector<std::uint64_t> order_;  // a permutation of every training pixel
  std::size_t next_ = 0;
  std::uint64_t epoch_seed_ = 0;  // order_ is the identity shuffled by mt19937_64(epoch_seed_)
  bool in_epoch_ = false;
  std::mt19937_64 rng_;
  nlohmann::json stored_;  // a resumed run's config.json
  int start_iteration_ = 0;
  double start_seconds_ = 0;
  std::vector<double> curve_;  // (iteration, loss, batch PSNR), about 100 points a run
  std::vector<Ray> rays_;
  std::vector<float> target_ldr_, target_hdr_;  // per ray: 3 values each
  std::vector<std::uint32_t> ray_view_;
  std::vector<std::int64_t> upsample_at_, occupancy_at_;
  double loss_ = 0, psnr_ = 0;
};

// --resume: the scene and the settings not given come from RUN/config.json.
void HexPlaneTraining::ReadRunToResume() {
  const std::filesystem::path config = o_.out / "config.json", checkpoint = o_.out / "checkpoint.bin";
  if (!std::filesystem::exists(config) || !std::filesystem::exists(checkpoint))
    Fail("train: --resume: {} has no config.json and checkpoint.bin to resume from",
         o_.out.string());
  stored_ = ReadJsonFile(config);
  const JsonField f(stored_, config.string());
  if (!stored_.is_object() || !stored_.contains("hexplane"))
    Fail("{}: not a HexPlane run (no \"hexplane\" settings) to resume with --method {}",
         config.string(), o_.method);
  const std::string data = f["data"].String();
  if (o_.data.empty()) o_.data = data;
  if (std::filesystem::weakly_canonical(o_.data) != std::filesystem::weakly_canonical(data))
    Fail("train: --resume: --data {} is not the run's scene {} ({})", o_.data.string(), data,
         config.string());
  if (!o_.resolution) o_.resolution = int(f.IntOr("resolution", 1, 1, 1 << 16));
  if (!o_.background) o_.background = float(f.NumberOr("background", 0.0));
  // The settings not given are the run's (a given one must agree: CheckResumedConfig).
  const HexPlaneConfig run = HexPlaneConfig::FromJson(stored_["hexplane"], config.string());
  if (o_.supervision == "auto")
    o_.supervision = run.ldr_loss && run.hdr_loss ? "ldr+hdr" : run.hdr_loss ? "hdr" : "ldr";
  if (!o_.iterations) o_.iterations = run.iterations;
  if (!o_.batch_rays) o_.batch_rays = run.batch_rays;
  if (!o_.voxels_init) o_.voxels_init = run.voxels_init;
  if (!o_.voxels_final) o_.voxels_final = run.voxels_final;
  if (!o_.time_grid_init) o_.time_grid_init = run.time_grid_init;
  if (!o_.time_grid_final) o_.time_grid_final = run.time_grid_final;
  if (!o_.seed) o_.seed = std::int64_t(run.seed);
  if (!o_.hdr_weight) o_.hdr_weight = run.hdr_weight;
  if (!o_.background_model) o_.background_model = run.background_model;
  const ExposureUnit unit = RecordedExposureUnit(stored_, config.string());
  if (o_.exposure_unit && *o_.exposure_unit != unit)
    Fail("train: --resume: --exposure-unit {} is not the run's ({}: {})",
         ExposureUnitName(*o_.exposure_unit), config.string(), ExposureUnitName(unit));
  o_.exposure_unit = unit;
}

// A resumed run trains with its own settings: any given one that resolves differently is refused.
void HexPlaneTraining::CheckResumedConfig() const {
  const nlohmann::json now = RunConfig(), then = stored_;
  std::vector<std::string> differ;
  for (const char* key : {"method", "resolution", "background"})
    if (now.value(key, nlohmann::json()) != then.value(key, nlohmann::json())) differ.push_back(key);
  for (const auto& [key, value] : now["hexplane"].items())
    if (!then["hexplane"].contains(key) || then["hexplane"][key] != value)
      differ.push_back("hexplane." + key);
  if (!differ.empty())
    Fail("train: --resume: the options give other settings than {} has ({}); resume with the "
         "run's own (or train a new run)",
         (o_.out / "config.json").string(), fmt::join(differ, ", "));
}

void HexPlaneTraining::SetUp() {
  if (o_.resume) ReadRunToResume();
  if (!o_.resolution) o_.resolution = 1;
  if (!o_.background) o_.background = 0.0f;
  if (*o_.resolution < 1) Fail("train: resolution {} must be >= 1", *o_.resolution);
  if (!o_.exposure_unit) o_.exposure_unit = ExposureUnit::kSeconds;
  dataset_ = LoadDataset(o_.data, {.exposure_unit = *o_.exposure_unit});
  bool has_hdr = !dataset_.train.empty();
  for (const Frame& f : dataset_.train) has_hdr = has_hdr && f.hdr_path.has_value();
  c_ = HexPlanePreset(o_.method, o_.supervision, has_hdr);
  if (o_.iterations) c_.iterations = *o_.iterations;
  if (o_.batch_rays) c_.batch_rays = *o_.batch_rays;
  if (o_.voxels_init) c_.voxels_init = *o_.voxels_init;
  if (o_.voxels_final) c_.voxels_final = *o_.voxels_final;
  if (o_.time_grid_init) c_.time_grid_init = *o_.time_grid_init;
  if (o_.time_grid_final) c_.time_grid_final = *o_.time_grid_final;
  if (o_.seed) c_.seed = std::uint64_t(*o_.seed);
  if (o_.hdr_weight) c_.hdr_weight = *o_.hdr_weight;
  if (o_.background_model) c_.background_model = *o_.background_model;
  ApplySceneBounds(dataset_, &c_);
  c_.background = *o_.background;
  if (std::string p = c_.Validate(); !p.empty()) Fail("train: {}", p);
  if (o_.resume) CheckResumedConfig();
  const float bg[3] = {c_.background, c_.background, c_.background};
  train_ = method::LoadViews(dataset_, Split::kTrain, bg, c_.hdr_loss, *o_.resolution);
  if (train_.empty()) Fail("{}: no training views", dataset_.root.string());
  test_ = method::CheckViews(dataset_, Split::kTest, bg, *o_.resolution);
  for (const TrainView& v : train_) {
    float max_value = 0;
    if (c_.hdr_loss) {
      const Image hdr = ReadImage(*v.hdr_path);
      for (std::size_t i = 0; i < hdr.num_pixels() * hdr.channels(); ++i)
        max_value = std::max(max_value, hdr.data()[i]);
    }
    hdr_max_.push_back(max_value > 0 ? max_value : 1.0f);
  }
  model_ = HexPlaneModel::Create(c_, int(train_.size()));
  adam_.emplace(c_.beta1, c_.beta2);
  for (int it : c_.upsample_at) upsample_at_.push_back(c_.Scaled(it));
  for (int it : c_.occupancy_at) occupancy_at_.push_back(c_.Scaled(it));
  rng_.seed(c_.seed);
}

// A resumed run's model, optimiser, generator and place in the pixel order.
void HexPlaneTraining::Restore() {
  const std::filesystem::path file = o_.out / "checkpoint.bin";
  const HexPlaneTrainState s = LoadTrainingCheckpoint(file, c_, &model_, &*adam_);
  if (int(model_.exposure_offset.size()) != (c_.color == ColorModel::kLdr ? 0 : int(train_.size())))
    Fail("{}: {} exposure offsets for {} training views", file.string(),
         model_.exposure_offset.size(), train_.size());
  if (s.iteration > c_.iterations)
    Fail("{}: {} iterations done, more than the run's {}", file.string(), s.iteration,
         c_.iterations);
  std::istringstream rng(s.rng);
  rng >> rng_;
  if (!rng) Fail("{}: the random generator's state does not read back", file.string());
  if (s.in_epoch) {
    NewEpoch(s.epoch_seed);
    if (s.next > order_.size())
      Fail("{}: pixel {} of {} in the order", file.string(), s.next, order_.size());
    next_ = std::size_t(s.next);
  }
  start_iteration_ = int(s.iteration);
  start_seconds_ = s.seconds;
  curve_ = s.curve;
  spdlog::info("hexplane: resuming {} at iteration {}", file.string(), start_iteration_);
}

nlohmann::json HexPlaneTraining::RunConfig() const {
  return {{"method", c_.method},
          {"data", std::filesystem::absolute(o_.data).string()},
          {"exposure_unit", ExposureUnitName(o_.exposure_unit.value_or(ExposureUnit::kSeconds))},
          {"resolution", *o_.resolution},
          {"background", c_.background},
          {"hdr", {{"method", c_.method}}},
          {"hexplane", c_.ToJson()}};
}

// The training curve as the Gaussian runs' results.json holds it (the harness reads it).
nlohmann::json HexPlaneTraining::CurveJson() const {
  nlohmann::json c = {{"iteration", nlohmann::json::array()},
                      {"loss", nlohmann::json::array()},
                      {"train_psnr", nlohmann::json::array()}};
  for (std::size_t i = 0; i + 2 < curve_.size(); i += 3) {
    c["iteration"].push_back(std::int64_t(curve_[i]));
    c["loss"].push_back(FiniteOrNull(curve_[i + 1]));
    c["train_psnr"].push_back(FiniteOrNull(curve_[i + 2]));
  }
  return c;
}

void HexPlaneTraining::SaveCheckpoint(int iterations_done, double seconds) const {
  HexPlaneTrainState s;
  s.iteration = iterations_done;
  s.seconds = seconds;
  std::ostringstream rng;
  rng << rng_;
  s.rng = rng.str();
  s.epoch_seed = epoch_seed_;
  s.next = next_;
  s.in_epoch = in_epoch_;
  s.curve = curve_;
  SaveTrainingCheckpoint(o_.out / "checkpoint.bin", model_, *adam_, s);
}

void HexPlaneTraining::FillPixelOrder() {
  order_.clear();
  for (std::size_t v = 0; v < train_.size(); ++v)
    for (int p = 0; p < train_[v].width() * train_[v].height(); ++p)
      order_.push_back((std::uint64_t(v) << 32) | std::uint64_t(p));
}

// A fresh permutation of every training pixel, as the reference's sampler after each pass; drawn
// from the identity by its own seed, so a checkpoint holds the seed instead of the permutation.
void HexPlaneTraining::NewEpoch(std::uint64_t seed) {
  FillPixelOrder();
  std::mt19937_64 shuffle(seed);
  std::shuffle(order_.begin(), order_.end(), shuffle);
  epoch_seed_ = seed;
  next_ = 0;
  in_epoch_ = true;
}

// The next batch of the shuffled pixels.
void HexPlaneTraining::MakeBatch(std::mt19937_64* rng) {
  rays_.clear();
  target_ldr_.clear();
  target_hdr_.clear();
  ray_view_.clear();
  for (int k = 0; k < c_.batch_rays; ++k) {
    if (!in_epoch_ || next_ == order_.size()) NewEpoch((*rng)());
    const std::uint64_t id = order_[next_++];
    const std::uint32_t v = std::uint32_t(id >> 32), p = std::uint32_t(id & 0xffffffffu);
    const TrainView& view = train_[v];
    const int w = view.width();
    rays_.push_back(PixelRay(view.camera, int(p % w), int(p / w), view.time,
                             float(std::log(std::max(view.exposure, 1e-30))), int(v)));
    ray_view_.push_back(v);
    for (int ch = 0; ch < 3; ++ch) {
      if (!view.rgb.empty()) target_ldr_.push_back(view.rgb[std::size_t(p) * 3 + ch] / 255.0f);
      if (c_.hdr_loss) target_hdr_.push_back(view.hdr_mu[std::size_t(p) * 3 + ch] / 65535.0f);
    }
  }
  if (target_ldr_.size() != rays_.size() * 3) Fail("train: the LDR training images are not held");
}

// MSE of the LDR output (and weight x MSE of the mu-law HDR) with its gradient.
double HexPlaneTraining::LossGradient(const std::vector<float>& out, std::vector<float>* dout) {
  const int K = RayChannels(model_);
  const std::size_t n = rays_.size();
  dout->assign(out.size(), 0.0f);
  double ldr = 0, hdr = 0;
  const float inv = 1.0f / float(n * 3);
  for (std::size_t r = 0; r < n; ++r)
    for (int ch = 0; ch < 3; ++ch) {
      const float d = out[r * K + ch] - target_ldr_[r * 3 + ch];
      ldr += double(d) * d;
      if (c_.ldr_loss) (*dout)[r * K + ch] = 2 * d * inv;
      if (!c_.hdr_loss) continue;
      const float scale = 1.0f / hdr_max_[ray_view_[r]], x = out[r * K + 3 + ch] * scale;
      const float e = MuLaw(x) - target_hdr_[r * 3 + ch];
      hdr += double(e) * e;
      (*dout)[r * K + 3 + ch] = c_.hdr_weight * 2 * e * inv * MuLawSlope(x) * scale;
    }
  psnr_ = -10.0 * std::log10(std::max(ldr / (n * 3), 1e-12));
  return (c_.ldr_loss ? ldr : 0.0) / (n * 3) + (c_.hdr_loss ? c_.hdr_weight * hdr / (n * 3) : 0.0);
}


// The reference's plane regularisers: TV on every plane (space-time planes weigh differences
// along time tv_time_ratio times), L1 as mean |value|, each weight decayed with the learning rate.
void HexPlaneTraining::Regularise(float lr_factor) {
  const auto apply = [&](const HexPlanes<float>& planes, HexPlanes<float>* grads, float tv,
                         float l1) {
    for (int i = 0; i < 3; ++i) {
      if (tv > 0) {
        TotalVariation(planes.space[i], 1.0f, 1.0f, tv * lr_factor, &grads->space[i]);
        TotalVariation(planes.time[i], 1.0f, c_.tv_time_ratio, tv * lr_factor, &grads->time[i]);
      }
      if (l1 > 0) {
        MeanAbs(planes.space[i], l1 * lr_factor, &grads->space[i]);
        MeanAbs(planes.time[i], l1 * lr_factor, &grads->time[i]);
      }
    }
  };
  apply(model_.density, &grads_->density, c_.tv_density, c_.l1_density);
  apply(model_.app, &grads_->app, c_.tv_app, c_.l1_app);
}

void HexPlaneTraining::Step(int it, std::mt19937_64* rng) {
  const float lr_factor = std::pow(c_.lr_decay_ratio, float(it) / float(c_.iterations));
  MakeBatch(rng);
  std::vector<float> jitter(model_.NumSamples());
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (float& j : jitter) j = u(*rng);
  std::vector<float> out, dout;
  batch_.Forward(model_, rays_, jitter.data(), &out);
  loss_ = LossGradient(out, &dout);
  if (!grads_ || grads_->density.space[0].size() != model_.density.space[0].size() ||
      grads_->density.time[0].size() != model_.density.time[0].size())
    grads_.emplace(model_);
  batch_.Backward(model_, dout, &*grads_);
  Regularise(lr_factor);
  adam_->BeginStep();
  const float lr_grid = c_.lr_grid * lr_factor, lr_nn = c_.lr_nn * lr_factor;
  for (int k = 0; k < 6; ++k) {
    adam_->Update(&model_.density.All()[k]->data, grads_->density.All()[k]->data, lr_grid);
    adam_->Update(&model_.app.All()[k]->data, grads_->app.All()[k]->data, lr_grid);
  }
  adam_->Update(&model_.density_basis, grads_->density_basis, lr_nn);
  adam_->Update(&model_.app_basis, grads_->app_basis, lr_nn);
  adam_->Update(&model_.mlp, grads_->mlp, lr_nn);
  if (!model_.exposure_offset.empty())
    adam_->Update(&model_.exposure_offset, grads_->exposure_offset, c_.lr_offset * lr_factor);
  // A handful of values seen by every ray that misses the scene: the planes' rate.
  if (!model_.background.empty()) adam_->Update(&model_.background, grads_->background, lr_grid);
}

// After iteration `it`: the occupancy grid, then the upsampling, at the reference's iterations
// scaled to this run's length; Adam starts afresh on upsampled planes (the reference makes a new
// optimiser).
void HexPlaneTraining::Schedules(int it) {
  if (std::find(occupancy_at_.begin(), occupancy_at_.end(), it) != occupancy_at_.end()) {
    if (model_.UpdateOccupancy()) {
      std::size_t kept = 0;
      for (std::uint8_t o : model_.occupancy.occupied) kept += o;
      spdlog::info("hexplane: iteration {}: occupancy grid {}^3, {:.1f}% occupied", it,
                   model_.occupancy.res[0],
                   100.0 * kept / std::max<std::size_t>(1, model_.occupancy.occupied.size()));
    } else {
      spdlog::warn("hexplane: iteration {}: no point reaches the occupancy threshold yet; the "
                   "occupancy grid is not updated",
                   it);
    }
  }
  const auto at = std::find(upsample_at_.begin(), upsample_at_.end(), it);
  if (at == upsample_at_.end()) return;
  const std::size_t k = std::size_t(at - upsample_at_.begin());
  const std::array<int, 3> grid = ResolutionOf(VoxelSchedule(c_)[k]);
  const int time_grid = TimeGridSchedule(c_)[k];
  model_.Upsample(grid, time_grid);
  adam_->Reset();
  spdlog::info("hexplane: iteration {}: planes upsampled to {}^3, time {}, {} samples per ray", it,
               grid[0], time_grid, model_.NumSamples());
}

HexPlaneTrainSummary HexPlaneTraining::Finish(int iterations, double seconds) {
  SaveCheckpoint(iterations, seconds);
  WriteJsonFile(o_.out / "config.json", RunConfig());
  HexPlaneTrainSummary s;
  s.iterations = iterations;
  s.train_seconds = seconds;
  s.test_metrics = test_.empty() ? nlohmann::json::object() : EvaluateHexPlane(model_, test_);
  const nlohmann::json results = {{"method", c_.method},
                                  {"test", s.test_metrics},
                                  {"train_seconds", seconds},
                                  {"seconds_per_iteration", seconds / std::max(1, iterations)},
                                  {"iterations", iterations},
                                  {"test_views", test_.size()},
                                  {"final_loss", loss_},
                                  {"final_train_batch_psnr", psnr_},
                                  {"threads", MaxThreads()},
                                  {"grid", model_.grid},
                                  {"time_grid", model_.time_grid},
                                  {"curve", CurveJson()}};
  WriteJsonFile(o_.out / "results.json", results);
  return s;
}

HexPlaneTrainSummary HexPlaneTraining::Run() {
  SetUp();
  std::filesystem::create_directories(o_.out);
  const RunFolderWriter writer(o_.out);  // its config, checkpoint and results are ours to write
  if (o_.resume) {
    Restore();
  } else {
    // The settings first: a run killed before its end resumes from them.
    std::filesystem::remove(o_.out / "results.json");
    WriteJsonFile(o_.out / "config.json", RunConfig());
  }
  Progress progress("train " + c_.method, c_.iterations, o_.progress);
  progress.Advance(start_iteration_);
  const auto start = std::chrono::steady_clock::now();
  double seconds = start_seconds_;
  int done = start_iteration_;
  while (done < c_.iterations) {
    Step(done, &rng_);
    Schedules(done);
    ++done;
    seconds = start_seconds_ +
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    progress.Advance(1, fmt::format("loss {:.5f} psnr {:.2f} samples {}/{}", loss_, psnr_,
                                    batch_.app_samples(), batch_.density_samples()));
    if (done % std::max(1, c_.iterations / 100) == 0 || done == c_.iterations)
      curve_.insert(curve_.end(), {double(done), loss_, psnr_});
    if (done == c_.iterations) break;
    if (o_.stop_after > 0 && done >= o_.stop_after) {
      SaveCheckpoint(done, seconds);  // interrupted: resumable, no results
      progress.Finish();
      return {.iterations = done, .train_seconds = seconds, .test_metrics = {}};
    }
    if (o_.checkpoint_every > 0 && done % o_.checkpoint_every == 0) SaveCheckpoint(done, seconds);
    if (o_.max_seconds > 0 && seconds >= o_.max_seconds) break;
  }
  progress.Finish();
  return Finish(done, seconds);
}

}  // namespace

HexPlaneTrainSummary TrainHexPlane(const HexPlaneTrainOptions& options) {
  if (options.out.empty()) Fail("train: --out is required");
  if (options.resolution && *options.resolution < 1)
    Fail("train: resolution {} must be >= 1", *options.resolution);
  if (options.checkpoint_every < 0 || options.stop_after < 0)
    Fail("train: checkpoint_every and stop_after must be >= 0");
  KeepFreedHeap();  // each step's matrices reuse the last step's pages (heap_policy.h)
  const ThreadLimit limit(options.threads);
  return HexPlaneTraining(options).Run();
}

}  // namespace hdr4d::baselines::hexplane
