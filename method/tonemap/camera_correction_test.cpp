// The per-camera correction (camera_correction.h): the inner mapper sees the view's camera's
// shift and nothing else changes; its gradient against central differences in double (per value
// and per image); the identity for other cameras; the lazy Adam step and its pull towards no
// gain; the checkpoint record and its errors.
#include "method/tonemap/camera_correction.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>
#include <random>
#include <sstream>
#include <vector>

#include "method/tonemap/tone_mapper_registry.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {

using testing::ErrorOf;

// A pointwise test mapper with a closed form: ldr_c = sigmoid(a_c (x + log e) + b_c), also
// written in double (Ldr) for the differences.
class SigmoidTestMapper final : public ToneMapper {
 public:
  static double Ldr(double x, double log_e, int c) {
    return 1.0 / (1.0 + std::exp(-(kA[c] * (x + log_e) + kB[c])));
  }
  const ToneMapperConfig& config() const override { return config_; }
  bool pointwise() const override { return true; }
  void BeginFrame(const ToneFrame& frame) override { log_e_ = frame.log_exposure; }
  void Map(const float* x, std::size_t n, float* ldr) const override {
    for (std::size_t i = 0; i < n * 3; ++i) ldr[i] = static_cast<float>(Ldr(x[i], log_e_, i % 3));
  }
  void MapBackward(const float* x, std::size_t n, const float* g, float* dx) override {
    ++backward_calls;
    for (std::size_t i = 0; i < n * 3; ++i) {
      const double y = Ldr(x[i], log_e_, i % 3);
      if (dx) dx[i] = static_cast<float>(g[i] * kA[i % 3] * y * (1 - y));
      params_[0] += g[i];  // a stand-in parameter gradient: the inner mapper keeps its own
    }
  }
  std::vector<float>& params() override { return params_; }
  std::vector<float>& grads() override { return params_; }
  void Save(std::ostream&) const override {}
  void Load(std::istream&, const std::string&) override {}
  int backward_calls = 0;

 private:
  static constexpr double kA[3] = {0.8, 1.1, 0.6}, kB[3] = {0.2, -0.1, 0.4};
  ToneMapperConfig config_;
  float log_e_ = 0;
  std::vector<float> params_ = {0.0f};
};

std::vector<float> Values(std::size_t n, unsigned seed, float lo, float hi) {
  std::mt19937 rng(seed);
  std::vector<float> v(n);
  for (float& x : v) x = std::uniform_real_distribution<float>(lo, hi)(rng);
  return v;
}

TEST(CameraCorrection, ShiftsTheInputOfTheViewsCameraOnly) {
  ToneMapperConfig tc;
  tc.num_times = 2;
  tc.context_window = 2;
  CameraCorrectedToneMapper wrapped(MakeToneMapper(tc), 3, {});
  std::unique_ptr<ToneMapper> plain = MakeToneMapper(tc);  // same seed: the same weights
  wrapped.log_gains() = {0, 0, 0, 0.3f, -0.2f, 0.1f, 0, 0, 0};
  const std::vector<float> x = Values(30, 1, -4, 3);
  std::vector<float> shifted = x;
  for (std::size_t i = 0; i < x.size(); ++i) shifted[i] += wrapped.log_gains()[3 + i % 3];
  std::vector<float> a(30), b(30);
  for (int camera : {1, -1, 7}) {
    const ToneFrame frame{.time_index = 1, .log_exposure = 0.4f, .camera_index = camera};
    wrapped.BeginFrame(frame);
    plain->BeginFrame(frame);
    wrapped.Map(x.data(), 10, a.data());
    plain->Map(camera == 1 ? shifted.data() : x.data(), 10, b.data());
    EXPECT_EQ(a, b) << "camera " << camera;  // -1 and beyond the rows: the identity
    wrapped.MapImage(x.data(), 5, 2, a.data());
    plain->MapImage(camera == 1 ? shifted.data() : x.data(), 5, 2, b.data());
    EXPECT_EQ(a, b) << "camera " << camera;
  }
  EXPECT_EQ(wrapped.params(), plain->params());  // the mapper's own parameters, passed through
  EXPECT_EQ(wrapped.config().kind, "dtm");
}

// dL/dd against central differences of L(d) = sum w ldr, computed in double from the closed
// form, through Map and MapImage; dL/dx is the inner mapper's at the shifted input.
TEST(CameraCorrection, GradientMatchesCentralDifferencesInDouble) {
  auto inner = std::make_unique<SigmoidTestMapper>();
  SigmoidTestMapper* test = inner.get();
  CameraCorrectedToneMapper m(std::move(inner), 2, {});
  m.log_gains() = {0.1f, -0.3f, 0.2f, -0.4f, 0.25f, 0.05f};
  const std::size_t n = 40;
  const std::vector<float> x = Values(n * 3, 2, -3, 2), w = Values(n * 3, 3, -1, 1);
  const float log_e = -0.5f;
  const auto loss = [&](const std::vector<double>& d) {
    double l = 0;
    for (std::size_t i = 0; i < n * 3; ++i)
      l += w[i] * SigmoidTestMapper::Ldr(double(x[i]) + d[i % 3], log_e, i % 3);
    return l;
  };
  for (bool image : {false, true}) {
    m.ZeroGrad();
    m.BeginFrame({.log_exposure = log_e, .camera_index = 1});
    std::vector<float> dx(n * 3);
    if (image) m.MapImageBackward(x.data(), 8, 5, w.data(), dx.data());
    else m.MapBackward(x.data(), n, w.data(), nullptr);  // null dL/dx: the gains still get theirs
    std::vector<double> d = {m.log_gains()[3], m.log_gains()[4], m.log_gains()[5]};
    for (int c = 0; c < 3; ++c) {
      const double h = 1e-5;
      std::vector<double> up = d, down = d;
      up[c] += h;
      down[c] -= h;
      const double numeric = (loss(up) - loss(down)) / (2 * h);
      EXPECT_NEAR(m.log_gain_grads()[3 + c], numeric, 1e-5 * std::abs(numeric) + 1e-5) << c;
      EXPECT_GT(std::abs(numeric), 0.05);  // a real check
      EXPECT_EQ(m.log_gain_grads()[c], 0.0f);  // camera 0 took no part
    }
    if (image) {
      for (std::size_t i = 0; i < n * 3; ++i) {
        const double y = SigmoidTestMapper::Ldr(double(x[i]) + d[i % 3], log_e, i % 3);
        const double a = std::array{0.8, 1.1, 0.6}[i % 3];
        EXPECT_NEAR(dx[i], w[i] * a * y * (1 - y), 1e-6);
      }
    }
  }
  EXPECT_EQ(test->backward_calls, 2);
  EXPECT_NE(test->params()[0], 0.0f);  // the inner mapper's parameters still learn
}

TEST(CameraCorrection, OtherCamerasGetNoGradientAndStepsPullTowardsNoGain) {
  CameraCorrectedToneMapper m(std::make_unique<SigmoidTestMapper>(), 3,
                              {.weight = 1.0, .lr = 0.01});
  m.log_gains() = {0.5f, -0.5f, 0.2f, 0.5f, 0.5f, 0.5f, 0.1f, 0.1f, 0.1f};
  const std::vector<float> x = Values(12, 4, -1, 1), zero(12, 0.0f);
  m.ZeroGrad();
  m.BeginFrame({.camera_index = -1});  // a held-out camera
  m.MapBackward(x.data(), 4, zero.data(), nullptr);
  EXPECT_EQ(m.Regulariser(), 0.0);
  const std::vector<float> before = m.log_gains();
  m.Step();
  EXPECT_EQ(m.log_gains(), before);  // nothing seen, nothing stepped
  for (int k = 0; k < 200; ++k) {
    m.ZeroGrad();
    m.BeginFrame({.camera_index = 0});
    m.MapBackward(x.data(), 4, zero.data(), nullptr);  // no data gradient: the pull alone
    if (k == 0) EXPECT_NEAR(m.Regulariser(), 0.25 + 0.25 + 0.04, 1e-6);
    m.Step();
  }
  for (int c = 0; c < 3; ++c) EXPECT_LT(std::abs(m.log_gains()[c]), 0.05f) << c;
  for (int i = 3; i < 9; ++i) EXPECT_EQ(m.log_gains()[i], before[i]);  // unseen rows stay
}

TEST(CameraCorrection, CheckpointRecordRoundTripsAndBadOnesAreErrors) {
  CameraCorrectedToneMapper m(std::make_unique<SigmoidTestMapper>(), 2, {});
  const std::vector<float> x = Values(6, 5, -1, 1), g = Values(6, 6, -1, 1);
  m.ZeroGrad();
  m.BeginFrame({.camera_index = 1});
  m.MapBackward(x.data(), 2, g.data(), nullptr);
  m.Step();
  const nlohmann::json trainer = {{kCameraCorrectionKey, m.ToJson()}};
  CameraCorrectedToneMapper back(std::make_unique<SigmoidTestMapper>(), 2, {});
  back.FromJson(nlohmann::json::parse(trainer.dump()), "ck.bin");
  EXPECT_EQ(back.ToJson(), m.ToJson());
  EXPECT_NE(back.log_gains()[3], 0.0f);

  const auto error = [&](nlohmann::json t) {
    return ErrorOf([&] { back.FromJson(t, "ck.bin"); });
  };
  EXPECT_NE(error(nlohmann::json::object()).find("--camera-correction"), std::string::npos);
  nlohmann::json bad = trainer;
  bad[kCameraCorrectionKey]["log_gain"] = {1, 2, 3};  // one camera, not two
  EXPECT_NE(error(bad).find("log_gain must be an array of 6"), std::string::npos);
  bad = trainer;
  bad[kCameraCorrectionKey]["adam_m"][0] = "nan";
  EXPECT_NE(error(bad).find("not a finite number"), std::string::npos);
  bad = trainer;
  bad[kCameraCorrectionKey]["adam_v"][0] = -1;
  EXPECT_NE(error(bad).find("negative"), std::string::npos);
  bad = trainer;
  bad[kCameraCorrectionKey]["adam_steps"][0] = 1.5;
  EXPECT_NE(error(bad).find("counts"), std::string::npos);
  EXPECT_NE(error(bad).find("ck.bin"), std::string::npos);
  EXPECT_EQ(back.ToJson(), m.ToJson());  // a refused record changed nothing
}

}  // namespace
}  // namespace hdr4d::method
