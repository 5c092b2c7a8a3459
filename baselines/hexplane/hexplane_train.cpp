#include "baselines/hexplane/hexplane_train.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <random>

#include "baselines/hexplane/hexplane_adam.h"
#include "baselines/hexplane/hexplane_render.h"
#include "baselines/hexplane/ray_batch.h"
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
  void SetUp();
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
  std::vector<Ray> rays_;
  std::vector<float> target_ldr_, target_hdr_;  // per ray: 3 values each
  std::vector<std::uint32_t> ray_view_;
  std::vector<std::int64_t> upsample_at_, occupancy_at_;
  double loss_ = 0, psnr_ = 0;
};

void HexPlaneTraining::SetUp() {
  dataset_ = LoadDataset(o_.data);
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
  if (dataset_.near) c_.near = float(*dataset_.near);
  if (dataset_.far) c_.far = float(*dataset_.far);
  c_.background = o_.background;
  if (std::string p = c_.Validate(); !p.empty()) Fail("train: {}", p);
  const float bg[3] = {o_.background, o_.background, o_.background};
  train_ = method::LoadViews(dataset_, Split::kTrain, bg, c_.hdr_loss, o_.resolution);
  if (train_.empty()) Fail("{}: no training views", dataset_.root.string());
  test_ = method::CheckViews(dataset_, Split::kTest, bg, o_.resolution);
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
}

// The next batch of the shuffled pixels (reshuffled when used up, as the reference's sampler).
void HexPlaneTraining::MakeBatch(std::mt19937_64* rng) {
  if (order_.empty()) {
    for (std::size_t v = 0; v < train_.size(); ++v)
      for (int p = 0; p < train_[v].width() * train_[v].height(); ++p)
        order_.push_back((std::uint64_t(v) << 32) | std::uint64_t(p));
    next_ = order_.size();
  }
  rays_.clear();
  target_ldr_.clear();
  target_hdr_.clear();
  ray_view_.clear();
  std::vector<float> mu;
  for (int k = 0; k < c_.batch_rays; ++k) {
    if (next_ == order_.size()) {
      std::shuffle(order_.begin(), order_.end(), *rng);
      next_ = 0;
    }
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
  model_.Save(o_.out / "checkpoint.bin");
  nlohmann::json config = {{"method", c_.method},
                           {"data", std::filesystem::absolute(o_.data).string()},
                           {"resolution", o_.resolution},
                           {"background", o_.background},
                           {"hdr", {{"method", c_.method}}},
                           {"hexplane", c_.ToJson()}};
  WriteJsonFile(o_.out / "config.json", config);
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
                                  {"time_grid", model_.time_grid}};
  WriteJsonFile(o_.out / "results.json", results);
  return s;
}

HexPlaneTrainSummary HexPlaneTraining::Run() {
  SetUp();
  std::filesystem::create_directories(o_.out);
  std::mt19937_64 rng(c_.seed);
  Progress progress("train " + c_.method, c_.iterations, o_.progress);
  const auto start = std::chrono::steady_clock::now();
  double seconds = 0;
  int it = 0;
  for (; it < c_.iterations; ++it) {
    Step(it, &rng);
    Schedules(it);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    progress.Advance(1, fmt::format("loss {:.5f} psnr {:.2f} samples {}/{}", loss_, psnr_,
                                    batch_.app_samples(), batch_.density_samples()));
    if (o_.max_seconds > 0 && seconds >= o_.max_seconds) {
      ++it;
      break;
    }
  }
  progress.Finish();
  return Finish(it, seconds);
}

}  // namespace

HexPlaneTrainSummary TrainHexPlane(const HexPlaneTrainOptions& options) {
  if (options.out.empty()) Fail("train: --out is required");
  if (options.resolution < 1) Fail("train: resolution {} must be >= 1", options.resolution);
  const ThreadLimit limit(options.threads);
  return HexPlaneTraining(options).Run();
}

}  // namespace hdr4d::baselines::hexplane
