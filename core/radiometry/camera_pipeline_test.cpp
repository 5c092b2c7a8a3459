// Each camera pipeline does what camera_pipeline*.h says, and a dataset synthesised through
// one records the hidden truth in synthesis.json while its JSON keeps the nominal exposures.
#include "core/radiometry/camera_pipeline.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include <fmt/format.h>

#include "core/dataset/dataset.h"
#include "core/dataset/demo_scene.h"
#include "core/files/json_util.h"
#include "core/image/image_io.h"
#include "core/radiometry/camera_pipeline_auto_exposure.h"
#include "core/radiometry/camera_pipeline_phone.h"
#include "core/radiometry/camera_pipeline_rig_mismatch.h"
#include "core/radiometry/camera_pipeline_vignetting.h"
#include "core/radiometry/exposure_stack.h"
#include "core/util/error.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;

PipelineView View(int camera, double time, double luminance) {
  return {.camera = camera, .time = time, .stats = {.log_mean = std::log(luminance)}};
}

Image Flat(int w, int h, float r, float g, float b) {
  Image image(w, h, 3, Encoding::kLinear);
  for (std::size_t p = 0; p < image.num_pixels(); ++p) {
    image.data()[p * 3] = r;
    image.data()[p * 3 + 1] = g;
    image.data()[p * 3 + 2] = b;
  }
  return image;
}

TEST(AutoExposure, BrightnessDoublesGainHalvesAfterTheLag) {
  const double lag = 0.05;
  std::vector<PipelineView> views;
  for (int k = 0; k <= 40; ++k) {
    const double t = k / 40.0;
    views.push_back(View(0, t, t < 0.5 ? 1.0 : 2.0));
  }
  const std::vector<double> g = AutoExposureGains(views, "rig", lag, 1.0);
  EXPECT_NEAR(g[0], g[19], 1e-12);  // steady before the step
  // One step (0.025 = lag / 2) after the change the meter has moved only 1 - e^-0.5 = 39%.
  EXPECT_NEAR(std::log(g[20] / g[19]), -(1 - std::exp(-0.5)) * std::log(2.0), 1e-9);
  EXPECT_GT(g[20] / g[19], 0.7);
  // Ten lags later the gain has halved (to within e^-10).
  EXPECT_NEAR(g[40] / g[19], 0.5, 1e-3);
  // No lag: at once. Strength 0.5: half the correction.
  const std::vector<double> now = AutoExposureGains(views, "rig", 0.0, 1.0);
  EXPECT_NEAR(now[20] / now[19], 0.5, 1e-12);
  const std::vector<double> half = AutoExposureGains(views, "rig", 0.0, 0.5);
  EXPECT_NEAR(half[20] / half[19], std::sqrt(0.5), 1e-12);
}

TEST(AutoExposure, RigWideGainsAreSharedPerCameraGainsAreNot) {
  // Camera 1 sees a scene 4x brighter than camera 0, at every time.
  std::vector<PipelineView> views;
  for (int k = 0; k < 5; ++k) {
    views.push_back(View(0, k / 4.0, 1.0 + k));
    views.push_back(View(1, k / 4.0, 4.0 * (1.0 + k)));
  }
  const std::vector<double> rig = AutoExposureGains(views, "rig", 0.1, 1.0);
  const std::vector<double> cam = AutoExposureGains(views, "camera", 0.1, 1.0);
  for (int k = 0; k < 5; ++k) {
    EXPECT_DOUBLE_EQ(rig[2 * k], rig[2 * k + 1]) << k;
    EXPECT_NEAR(cam[2 * k] / cam[2 * k + 1], 4.0, 1e-9) << k;  // each meters its own view
  }
  EXPECT_LT(rig[8], rig[0]);  // the scene brightens, the gain falls
}

TEST(PhoneCurve, ShoulderAndToeFollowTheContent) {
  const FrameStatistics dim{.log_mean = std::log(0.05), .log_low = std::log(0.002),
                            .log_high = std::log(0.2)};
  FrameStatistics bright_highlights = dim;
  bright_highlights.log_high = std::log(0.8);
  FrameStatistics deep_shadows = dim;
  deep_shadows.log_low = std::log(0.0002);
  const PhoneCurve a = FitPhoneCurve(dim, 1.0);
  const PhoneCurve b = FitPhoneCurve(bright_highlights, 1.0);
  const PhoneCurve c = FitPhoneCurve(deep_shadows, 1.0);
  EXPECT_NEAR(a.white, 0.2, 1e-12);
  EXPECT_NEAR(b.white, 0.8, 1e-12);  // the shoulder moved with the highlights
  EXPECT_NEAR(c.white, 0.2, 1e-12);
  EXPECT_LT(c.mid, a.mid);            // the mid and the toe moved with the shadows
  EXPECT_NEAR(a.mid, std::sqrt(0.002 / 0.2), 1e-12);
  // The curve: white at x_hi, the toe value at x_lo.
  const BentCrf curve(std::make_shared<FilmicCrf>(a.contrast, a.mid), 1.0, a.white);
  EXPECT_DOUBLE_EQ(curve.Apply(0.2), 1.0);
  EXPECT_NEAR(curve.Apply(0.002), kPhoneToe, 1e-9);
  EXPECT_NEAR(curve.Inverse(0.5), 0.2 * FilmicCrf(a.contrast, a.mid).Inverse(0.5), 1e-12);
  // The exposure scales the curve's points with it.
  EXPECT_NEAR(FitPhoneCurve(dim, 2.0).white, 0.4, 1e-12);
  // Extremes stay finite and within the documented clamps.
  const PhoneCurve black = FitPhoneCurve({.log_mean = -14, .log_low = -14, .log_high = -14}, 1);
  EXPECT_NEAR(black.white, 1e-3, 1e-15);
  EXPECT_GE(black.contrast, 0.4);
  EXPECT_LE(black.contrast, 3.0);
}

TEST(PhoneCurve, WhiteBalanceDriftChangesChannelRatiosOverTime) {
  const auto w0 = WhiteBalanceDrift(0, 0.0, 0.1, 1.0);
  const auto w1 = WhiteBalanceDrift(0, 0.25, 0.1, 1.0);
  EXPECT_DOUBLE_EQ(w0[0], 1.0);  // sin(0) = 0 for camera 0
  EXPECT_NEAR(std::log(w1[0] / w1[2]), 0.2, 1e-12);  // 2a at the crest
  EXPECT_DOUBLE_EQ(w1[1], 1.0);
  // Another camera drifts with another phase.
  EXPECT_NE(WhiteBalanceDrift(1, 0.0, 0.1, 1.0)[0], w0[0]);
}

TEST(PhonePipeline, GreySceneGetsDriftingColourAndFittedCurve) {
  const Image grey = Flat(8, 8, 0.1f, 0.1f, 0.1f);
  CameraPipelineOptions options{.name = "phone", .ae_lag = 0};
  std::vector<PipelineView> views;
  for (int k = 0; k < 4; ++k) {
    PipelineView v = View(0, k / 4.0, 0.1);
    v.stats = MeasureFrame(grey, 1, 99);
    views.push_back(v);
  }
  const auto plan = PlanViews(options, views, std::make_shared<FilmicCrf>(), 1.0);
  const LdrSynthesisOptions ldr{.exposure = 1.0, .bits = 0};
  const Image at0 = SynthesizeView(grey, plan[0], options, FilmicCrf(), ldr);
  const Image at1 = SynthesizeView(grey, plan[1], options, FilmicCrf(), ldr);
  EXPECT_FLOAT_EQ(at0.at(0, 0, 0), at0.at(0, 0, 2));  // no drift at t = 0
  EXPECT_GT(at1.at(0, 0, 0), at1.at(0, 0, 2) + 0.01);  // reddish a quarter-period later
  ASSERT_TRUE(plan[1].curve.is_object());
  EXPECT_NEAR(plan[1].curve["white"].get<double>(), 0.1, 1e-6);
}

TEST(RigMismatch, CamerasDifferAsSpecifiedAndTheReferenceDoesNot) {
  const RigCameraDifference ref = DrawRigCamera(3, 0, true, 0.3, 0.1, 0.05);
  EXPECT_EQ(ref.gain, 1.0);
  EXPECT_EQ(ref.exponent, 1.0);
  for (int camera = 1; camera < 20; ++camera) {
    const RigCameraDifference d = DrawRigCamera(3, camera, false, 0.3, 0.1, 0.05);
    EXPECT_LE(std::abs(std::log(d.gain)), 0.3);
    EXPECT_LE(std::abs(d.exponent - 1), 0.1);
    for (int r = 0; r < 3; ++r) {
      // Each row is a channel gain within e^(+-C) times a row summing to 1.
      const double sum = d.colour[r * 3] + d.colour[r * 3 + 1] + d.colour[r * 3 + 2];
      EXPECT_LE(std::abs(std::log(sum)), 0.05 + 1e-12);
    }
    // A camera's draw depends on the seed and itself only.
    EXPECT_EQ(d.gain, DrawRigCamera(3, camera, false, 0.3, 0.1, 0.05).gain);
    EXPECT_NE(d.gain, DrawRigCamera(4, camera, false, 0.3, 0.1, 0.05).gain);
  }
  // Through the images: the same radiance, three cameras, three results; camera 0 is the plain
  // response.
  const Image hdr = Flat(4, 4, 0.2f, 0.3f, 0.1f);
  const CameraPipelineOptions options{.name = "rig-mismatch", .seed = 3};
  const auto plan = PlanViews(options, {View(0, 0, 1), View(1, 0, 1), View(2, 0, 1)},
                              std::make_shared<FilmicCrf>(), 1.0);
  const LdrSynthesisOptions ldr{.exposure = 1.0, .bits = 0};
  const Image a = SynthesizeView(hdr, plan[0], options, FilmicCrf(), ldr);
  const Image b = SynthesizeView(hdr, plan[1], options, FilmicCrf(), ldr);
  const Image c = SynthesizeView(hdr, plan[2], options, FilmicCrf(), ldr);
  EXPECT_FLOAT_EQ(a.at(0, 0, 1), static_cast<float>(FilmicCrf().Apply(0.3f)));
  EXPECT_NE(a.at(0, 0, 1), b.at(0, 0, 1));
  EXPECT_NE(b.at(0, 0, 1), c.at(0, 0, 1));
}

TEST(Vignetting, FallsOffRadiallyAsDocumented) {
  const int w = 41, h = 21;
  EXPECT_NEAR(VignettingFactor(20, 10, w, h, 0.4), 1.0, 1e-3);  // the centre pixel
  const double corner = VignettingFactor(0, 0, w, h, 0.4);
  const double r_sq = (20.0 * 20.0 + 10.0 * 10.0) / (0.25 * (w * w + h * h));  // centre (0.5, 0.5)
  EXPECT_NEAR(corner, 1 - 0.4 * r_sq, 1e-12);
  EXPECT_NEAR(corner, 0.6, 0.05);
  double previous = 2;
  for (int x = 20; x < w; ++x) {  // monotone along a radius
    const double v = VignettingFactor(x, 10, w, h, 0.4);
    EXPECT_LT(v, previous);
    previous = v;
  }
  // In an image: a flat scene through a linear response shows the same factor.
  const CameraPipelineOptions options{.vignetting = 0.4};
  const LdrSynthesisOptions ldr{.exposure = 1.0, .bits = 0};
  const Image out = SynthesizeView(Flat(w, h, 0.5f, 0.5f, 0.5f), {}, options, LinearCrf(), ldr);
  EXPECT_NEAR(out.at(0, 0, 1), 0.5 * corner, 1e-6);
  EXPECT_NEAR(out.at(20, 10, 1), 0.5 * VignettingFactor(20, 10, w, h, 0.4), 1e-6);
}

TEST(CameraPipeline, FixedIsPlainSynthesisAndBadOptionsAreRefused) {
  Image hdr = Flat(5, 3, 0.1f, 0.7f, 2.0f);
  hdr.data()[4] = 0.01f;
  const LdrSynthesisOptions ldr{.exposure = 0.7, .noise = {.full_well = 100, .seed = 5}};
  EXPECT_EQ(SynthesizeView(hdr, {}, {}, FilmicCrf(), ldr).values(),
            SynthesizeLdr(hdr, FilmicCrf(), ldr).values());
  EXPECT_THROW((CameraPipelineOptions{.name = "iphone"}.Validate()), Error);
  EXPECT_THROW((CameraPipelineOptions{.ae_scope = "everyone"}.Validate()), Error);
  EXPECT_THROW((CameraPipelineOptions{.ae_lag = -1}.Validate()), Error);
  EXPECT_THROW((CameraPipelineOptions{.vignetting = 1.5}.Validate()), Error);
  EXPECT_THROW((CameraPipelineOptions{.wb_period = 0}.Validate()), Error);
  EXPECT_THROW((CameraPipelineOptions{.tone_low_percentile = 60, .tone_high_percentile = 40}
                    .Validate()),
               Error);
  // A radiance that is not one is still refused, pixel named, through any pipeline.
  hdr.data()[0] = -1;
  EXPECT_THROW(SynthesizeView(hdr, {}, {.name = "phone"}, FilmicCrf(), ldr), Error);
}

Dataset SmallScene(const fs::path& root) {
  DemoSceneOptions options;
  options.width = options.height = 24;
  options.num_timestamps = 3;
  options.num_cameras = 2;
  options.samples_per_axis = 1;
  return MakeDemoScene(options, root);
}

TEST(DatasetPipeline, RecordsTheHiddenTruthAndKeepsTheJson) {
  testing::TempDir dir;
  const Dataset dataset = SmallScene(dir.path());
  const std::string train_json = testing::ReadTextFile(dir / "transforms_train.json");
  SynthesizeDatasetLdr(dir.path(), {});
  const std::string fixed = testing::ReadTextFile(dataset.train[0].image_path);
  EXPECT_FALSE(ReadJsonFile(dir / "synthesis.json").contains("pipeline"));

  for (const std::string name : {"auto-exposure", "phone", "rig-mismatch"}) {
    SCOPED_TRACE(name);
    const DatasetSynthesisOptions options{.pipeline = {.name = name, .vignetting = 0.2}};
    SynthesizeDatasetLdr(dir.path(), options);
    EXPECT_EQ(testing::ReadTextFile(dir / "transforms_train.json"), train_json);
    const nlohmann::json manifest = ReadJsonFile(dir / "synthesis.json");
    ASSERT_TRUE(manifest.contains("pipeline")) << manifest.dump();
    const nlohmann::json& record = manifest["pipeline"];
    EXPECT_EQ(record["name"], name);
    EXPECT_EQ(record["vignetting"], 0.2);
    // One view per HDR image: cameras x timestamps over both splits.
    std::set<fs::path> hdrs;
    for (const Frame* f : dataset.AllFrames()) hdrs.insert(*f->hdr_path);
    ASSERT_EQ(record["views"].size(), hdrs.size());
    for (const nlohmann::json& v : record["views"]) {
      EXPECT_TRUE(v["gain"].is_number());
      EXPECT_EQ(v["white_balance"].size(), 3u);
      EXPECT_EQ(v["colour"].size(), 9u);
      EXPECT_TRUE(fs::exists(dir / v["hdr"].get<std::string>()));
      if (name == "phone") {
        EXPECT_TRUE(v["curve"].contains("white"));
      }
    }
    EXPECT_NE(testing::ReadTextFile(dataset.train[0].image_path), fixed);
  }
  // merge-hdr does not invert a pipeline with the recorded response.
  EXPECT_NE(testing::ErrorOf([&] { MergeDatasetExposures(dir.path(), dir / "m", {}); })
                .find("camera pipeline 'rig-mismatch'"),
            std::string::npos);
  // Back to the default: the same bytes as before, and no record.
  SynthesizeDatasetLdr(dir.path(), {});
  EXPECT_EQ(testing::ReadTextFile(dataset.train[0].image_path), fixed);
  EXPECT_FALSE(ReadJsonFile(dir / "synthesis.json").contains("pipeline"));
}

TEST(DatasetPipeline, RigWideAutoExposureSharesAGainPerTimestamp) {
  testing::TempDir dir;
  SmallScene(dir.path());
  for (const std::string scope : {"rig", "camera"}) {
    SynthesizeDatasetLdr(dir.path(), {.pipeline = {.name = "auto-exposure", .ae_scope = scope}});
    const nlohmann::json manifest = ReadJsonFile(dir / "synthesis.json");
    ASSERT_TRUE(manifest.contains("pipeline"));
    const nlohmann::json& views = manifest["pipeline"]["views"];
    ASSERT_EQ(views.size(), 6u);  // 2 cameras x 3 timestamps
    std::map<double, std::set<double>> gains_at;  // time -> the distinct gains then
    for (const nlohmann::json& v : views)
      gains_at[v["time"].get<double>()].insert(v["gain"].get<double>());
    ASSERT_EQ(gains_at.size(), 3u);
    for (const auto& [t, gains] : gains_at) {
      if (scope == "rig") EXPECT_EQ(gains.size(), 1u) << t;
      else EXPECT_GT(gains.size(), 1u) << t;  // the demo's cameras see different brightness
    }
  }
}

// A dataset whose JSON names no camera_id: each distinct pose is a camera.
TEST(DatasetPipeline, CamerasWithoutIdsAreTheirPoses) {
  testing::TempDir dir;
  SmallScene(dir.path());
  for (const char* split : {"train", "test"}) {
    const fs::path file = dir / fmt::format("transforms_{}.json", split);
    nlohmann::json j = ReadJsonFile(file);
    for (nlohmann::json& f : j["frames"]) f.erase("camera_id");
    WriteJsonFile(file, j);
  }
  SynthesizeDatasetLdr(dir.path(), {.pipeline = {.name = "rig-mismatch"}});
  const nlohmann::json manifest = ReadJsonFile(dir / "synthesis.json");
  ASSERT_TRUE(manifest.contains("pipeline"));
  // camera number -> the camera part of its HDR files' names ("hdr/cam00_t000.exr").
  std::map<int, std::set<std::string>> files_of;
  for (const nlohmann::json& v : manifest["pipeline"]["views"])
    files_of[v["camera"].get<int>()].insert(v["hdr"].get<std::string>().substr(0, 9));
  ASSERT_EQ(files_of.size(), 2u);
  EXPECT_EQ(files_of[0], (std::set<std::string>{"hdr/cam00"}));
  EXPECT_EQ(files_of[1], (std::set<std::string>{"hdr/cam01"}));
}

}  // namespace
}  // namespace hdr4d
