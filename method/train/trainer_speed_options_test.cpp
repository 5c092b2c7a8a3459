// Issue 55's training options end to end on a tiny scene: --reference is the old defaults bit for
// bit, visible-set Adam resumes exactly, and --iterations auto stops at the same iteration
// whether or not the run was interrupted.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/files/json_util.h"
#include "core/util/error.h"
#include "method/run/gaussian_scene.h"
#include "method/train/checkpoint.h"
#include "method/train/tiny_run_test_util.h"
#include "method/train/trainer.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {
namespace fs = std::filesystem;
using hdr4d::testing::TempDir;

// As trainer_test's SmallRun, another seed.
TrainOptions TinyRun(const fs::path& scene, const fs::path& run, int iterations) {
  return train_testing::TinyRunOptions(scene, run, iterations, /*seed=*/5);
}

// Eight cameras at five times: a view sees part of the model (4D Gaussians outside its time).
void MakeTinyScene(const fs::path& root, int size = 24) {
  GaussianSceneOptions s;
  s.size = size;
  s.num_gaussians = 12;
  s.num_cameras = 4;
  s.num_timestamps = 5;
  MakeGaussianScene(s, root);
}

void ExpectSameState(const fs::path& a, const fs::path& b) {
  const Checkpoint ca = LoadCheckpoint(a / "checkpoint.bin");
  const Checkpoint cb = LoadCheckpoint(b / "checkpoint.bin");
  EXPECT_EQ(ca.model.xyz, cb.model.xyz);
  EXPECT_EQ(ca.model.opacity_logit, cb.model.opacity_logit);
  EXPECT_EQ(ca.model.t, cb.model.t);
  EXPECT_EQ(ca.model.color_dc, cb.model.color_dc);
  EXPECT_EQ(ca.model.color_rest, cb.model.color_rest);
  EXPECT_TRUE(ca.adam_state == cb.adam_state);
  EXPECT_EQ(ca.extra_floats, cb.extra_floats);
}

// Trains `run(name, split_at)`, then resumes it with a cap of `cap` iterations: what a run
// interrupted at `split_at` ends with.
TrainSummary InterruptAndResume(const std::function<TrainOptions(const char*, int)>& run,
                                const char* name,
                                int split_at,
                                int cap) {
  Train(run(name, split_at));
  TrainOptions rest = run(name, cap);
  rest.resume = true;
  return Train(rest);
}

// A run of `run(name, iterations)` stopped at `split_at` and resumed to the end gives the same
// losses as `straight` (the uninterrupted run in dir / "straight") and the same final state.
void ExpectResumesExactly(const std::function<TrainOptions(const char*, int)>& run,
                          int split_at,
                          const TrainSummary& straight,
                          const fs::path& dir) {
  Train(run("split", split_at));
  TrainOptions rest = run("split", static_cast<int>(straight.loss_curve.size()));
  rest.resume = true;
  const TrainSummary resumed = Train(rest);
  EXPECT_EQ(resumed.loss_curve, straight.loss_curve);
  ExpectSameState(dir / "split", dir / "straight");
}

TEST(TrainerSpeedOptions, ReferenceIsTheOldDefaultsBitForBit) {
  TempDir dir;
  MakeTinyScene(dir / "scene");
  TrainOptions reference = TinyRun(dir / "scene", dir / "reference", 60);
  reference.reference = true;
  TrainOptions old = TinyRun(dir / "scene", dir / "old", 60);
  old.optimization.visible_adam = false;  // the defaults before issue 55, set explicitly
  old.optimization.stop_window = 0;
  const TrainSummary a = Train(reference);
  const TrainSummary b = Train(old);
  EXPECT_EQ(a.loss_curve, b.loss_curve);
  ExpectSameState(dir / "reference", dir / "old");
  EXPECT_EQ(ReadJsonFile(dir / "reference" / "config.json")["reference"], true);
  // The dense optimiser's state is the format of before (version 1), byte for byte.
  const Checkpoint c = LoadCheckpoint(dir / "reference" / "checkpoint.bin");
  ASSERT_GT(c.adam_state.size(), 12u);
  EXPECT_EQ(c.adam_state[8], 1);
  EXPECT_FALSE(ReadJsonFile(dir / "reference" / "results.json").contains("stopped"));
}

// run(name, iterations, on): a tiny run of MakeTinyScene's scene (in dir) into dir/name, with
// `set(options, on)` applied: one option's runs with it and without it.
template <typename Set>
auto TinyRunsWith(const TempDir& dir, Set set) {
  return [&dir, set](const char* name, int iterations, bool on) {
    TrainOptions o = TinyRun(dir / "scene", dir / name, iterations);
    set(o, on);
    return o;
  };
}

TEST(TrainerSpeedOptions, VisibleAdamDiffersFromDenseAndResumesExactly) {
  TempDir dir;
  MakeTinyScene(dir / "scene");
  const auto run = TinyRunsWith(
      dir, [](TrainOptions& o, bool visible) { o.optimization.visible_adam = visible; });
  const TrainSummary dense = Train(run("dense", 60, false));
  const TrainSummary straight = Train(run("straight", 60, true));
  EXPECT_NE(dense.loss_curve, straight.loss_curve) << "no Gaussian was ever unseen";
  // Split between densifications, rows behind their step.
  ExpectResumesExactly([&](const char* name, int it) { return run(name, it, true); }, 37,
                       straight, dir.path());
}

TEST(TrainerSpeedOptions, IterationsAutoStopsDeterministicallyAndResumes) {
  TempDir dir;
  MakeTinyScene(dir / "scene");
  auto run = [&](const char* name, int iterations) {
    TrainOptions o = TinyRun(dir / "scene", dir / name, iterations);
    o.optimization.stop_window = 10;
    o.optimization.stop_tolerance = 0.9;  // any window not 90% better than the one before
    return o;
  };
  const TrainSummary a = Train(run("a", 400));
  // Both windows after densify_until (50): the first check is at 70.
  EXPECT_EQ(a.iterations, 70);
  EXPECT_TRUE(a.stopped_flat);
  EXPECT_FALSE(a.stopped_by_time);
  const nlohmann::json stopped = ReadJsonFile(dir / "a" / "results.json")["stopped"];
  EXPECT_EQ(stopped["reason"], "loss_plateau");
  EXPECT_EQ(stopped["iteration"], 70);
  EXPECT_EQ(stopped["window"], 10);
  EXPECT_LT(stopped["improvement"].get<double>(), 0.9);
  const TrainSummary b = Train(run("b", 400));
  EXPECT_EQ(b.loss_curve, a.loss_curve);
  // Interrupted at 65 and resumed: the same stop, the same state.
  const TrainSummary c = InterruptAndResume(run, "c", 65, 400);
  EXPECT_EQ(c.iterations, 70);
  EXPECT_EQ(c.loss_curve, a.loss_curve);
  ExpectSameState(dir / "c", dir / "a");
  // A run that stopped is finished: resumed again, nothing is trained.
  TrainOptions rest = run("c", 400);
  rest.resume = true;
  const TrainSummary again = Train(rest);
  EXPECT_EQ(again.iterations, 70);
  EXPECT_TRUE(again.stopped_flat);
}

// The tiny scene with a val split: a copy of its test split.
void MakeTinySceneWithVal(const fs::path& root) {
  MakeTinyScene(root);
  fs::copy_file(root / "transforms_test.json", root / "transforms_val.json");
}

// --iterations auto --stop-on-val every 10 iterations, with a tolerance no evaluation reaches.
TrainOptions StopOnValRun(const fs::path& scene, const fs::path& run, int iterations) {
  TrainOptions o = TinyRun(scene, run, iterations);
  o.optimization.stop_window = 10;
  o.optimization.stop_tolerance = 0.9;
  o.optimization.stop_on_val = true;
  return o;
}

// StopOnValRun with one more switch of OptimizationOptions on, as run(name, iterations).
std::function<TrainOptions(const char*, int)> StopOnValRunsWith(const fs::path& dir,
                                                                bool OptimizationOptions::*flag) {
  return [dir, flag](const char* name, int iterations) {
    TrainOptions o = StopOnValRun(dir / "scene", dir / name, iterations);
    o.optimization.*flag = true;
    return o;
  };
}

// run("a", 400) trained to its val stop, which the tolerance puts at 40; its summary and results.
std::pair<TrainSummary, nlohmann::json> TrainToTheValStop(
    const TempDir& dir, const std::function<TrainOptions(const char*, int)>& run) {
  const TrainSummary a = Train(run("a", 400));
  EXPECT_EQ(a.iterations, 40);
  return {a, ReadJsonFile(dir / "a" / "results.json")};
}

// --stop-on-val: the stop is decided on the val split (here a copy of the test split), scored
// every --stop-window iterations, before that iteration's densification and opacity reset (the
// tiny run densifies every 10 and resets at 30); with a tolerance nothing reaches, the first
// evaluation stays the best and the run stops three evaluations later, on the model the last
// one scored. An interrupted run stops at the same iteration; a scene without a val split is
// refused.
TEST(TrainerSpeedOptions, StopOnValStopsOnTheValSplitAndResumes) {
  TempDir dir;
  MakeTinySceneWithVal(dir / "scene");
  auto run = [&](const char* name, int iterations) {
    return StopOnValRun(dir / "scene", dir / name, iterations);
  };
  const auto [a, r] = TrainToTheValStop(dir, run);
  EXPECT_TRUE(a.stopped_flat);
  EXPECT_EQ(r["stopped"]["reason"], "val_plateau");
  // The val views are the test views: the final scores are the last val reading's, to the bit,
  // so nothing (no densification at 40) changed the model after it was scored.
  EXPECT_EQ(r["test"]["psnr"].get<double>(), r["val_curve"].back()["psnr"].get<double>());
  EXPECT_EQ(r["stopped"]["best_val_iteration"], 10);
  std::vector<int> evaluated;
  for (const nlohmann::json& e : r.at("val_curve")) {
    evaluated.push_back(e.at("iteration").get<int>());
    EXPECT_TRUE(e.at("psnr").is_number());
  }
  EXPECT_EQ(evaluated, (std::vector<int>{10, 20, 30, 40}));
  // Interrupted at 25 and resumed: the same stop, the same state.
  const TrainSummary b = InterruptAndResume(run, "b", 25, 400);
  EXPECT_EQ(b.iterations, 40);
  EXPECT_EQ(b.loss_curve, a.loss_curve);
  ExpectSameState(dir / "b", dir / "a");
  // Without a val split: refused, naming the scene.
  fs::remove(dir / "scene" / "transforms_val.json");
  try {
    Train(run("c", 400));
    ADD_FAILURE() << "a scene without a val split was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no val split"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find((dir / "scene").string()), std::string::npos);
  }
  // Without --iterations auto (no window) it is refused before anything is read.
  TrainOptions no_window = run("d", 400);
  no_window.optimization.stop_window = 0;
  EXPECT_NE(no_window.Validate().find("--stop-on-val"), std::string::npos);
}

// --keep-best-val: the same stop (the first evaluation the best, the stop at 40) ends on the model
// the best one scored, taken back from RUN/best_val.bin. A run that reaches its length first
// keeps its last model and the file, so that a longer resumed run can still take it back; a
// damaged file costs a warning and the last model, never the run.
TEST(TrainerSpeedOptions, KeepBestValEndsOnTheBestValModel) {
  TempDir dir;
  MakeTinySceneWithVal(dir / "scene");
  const auto run = StopOnValRunsWith(dir.path(), &OptimizationOptions::keep_best_val);
  const auto [a, r] = TrainToTheValStop(dir, run);
  EXPECT_EQ(r["stopped"]["reason"], "val_plateau");
  EXPECT_EQ(r["stopped"]["best_val_iteration"], 10);
  // The val views are the test views: the final scores are the best reading's (the model as
  // scored, before the densification at 10), and the count is its. Within float rounding: the
  // final scores render every colour band switched on by 40; those the model of 10 had not used
  // are zero.
  EXPECT_EQ(r["stopped"]["model_iteration"], 10);
  EXPECT_EQ(a.model_iteration, 10);
  EXPECT_NEAR(r["test"]["psnr"].get<double>(), r["val_curve"][0]["psnr"].get<double>(), 1e-6);
  EXPECT_NE(r["test"]["psnr"].get<double>(), r["val_curve"].back()["psnr"].get<double>());
  EXPECT_EQ(a.gaussians, r["val_curve"][0]["gaussians"].get<std::size_t>());

  EXPECT_FALSE(fs::exists(dir / "a" / "best_val.bin"));  // its model is in the checkpoint now
  EXPECT_EQ(LoadCheckpoint(dir / "a" / "checkpoint.bin").model.size(), a.gaussians);
  // Resumed when finished: nothing to do, the kept model stays (the stop is not run again).
  TrainOptions again = run("a", 400);
  again.resume = true;
  const TrainSummary finished = Train(again);
  EXPECT_EQ(finished.gaussians, a.gaussians);
  EXPECT_EQ(finished.model_iteration, 10);
  // With a test curve, the last model is scored at the stop as well (what the option gave up),
  // then the kept one, marked with its iteration.
  TrainOptions curve = run("t", 400);
  curve.test_every = 10;
  Train(curve);
  const nlohmann::json tc = ReadJsonFile(dir / "t" / "results.json").at("test_curve");
  ASSERT_EQ(tc.size(), 5u);
  EXPECT_EQ(tc[3]["iteration"], 40);
  EXPECT_EQ(tc[3]["psnr"].get<double>(), r["val_curve"][3]["psnr"].get<double>());
  EXPECT_FALSE(tc[3].contains("model_iteration"));
  EXPECT_EQ(tc[4]["iteration"], 40);
  EXPECT_EQ(tc[4]["model_iteration"], 10);
  EXPECT_NEAR(tc[4]["psnr"].get<double>(), tc[0]["psnr"].get<double>(), 1e-6);
  // Interrupted at 25 and resumed: the same stop and the same kept model.
  const TrainSummary b = InterruptAndResume(run, "b", 25, 400);
  EXPECT_EQ(b.model_iteration, 10);
  ExpectSameState(dir / "b", dir / "a");
  // Resumed to train on without the val stop (as the README says): from the kept model.
  TrainOptions on = run("b", 50);
  on.resume = true;
  on.optimization.stop_on_val = false;
  on.optimization.stop_window = 0;
  EXPECT_EQ(Train(on).iterations, 50);
  // At its length (30) before the stop: the last model, and the file stays.
  const TrainSummary e = Train(run("e", 30));
  EXPECT_EQ(e.iterations, 30);
  EXPECT_EQ(e.model_iteration, 30);
  EXPECT_EQ(ReadJsonFile(dir / "e" / "results.json")["stopped"]["model_iteration"], 30);
  EXPECT_TRUE(fs::exists(dir / "e" / "best_val.bin"));
  // Resumed on to the stop with that file damaged: a warning, and the last model is kept.
  {
    std::fstream f(dir / "e" / "best_val.bin", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(100);
    f.put('\x5a');
  }
  TrainOptions longer = run("e", 400);
  longer.resume = true;
  const TrainSummary g = Train(longer);
  EXPECT_EQ(g.iterations, 40);
  EXPECT_EQ(g.model_iteration, 40);
  EXPECT_EQ(ReadJsonFile(dir / "e" / "results.json")["stopped"]["reason"], "val_plateau");
  // Without --stop-on-val it is refused, naming both options.
  TrainOptions alone = TinyRun(dir / "scene", dir / "f", 40);
  alone.optimization.keep_best_val = true;
  try {
    Train(alone);
    ADD_FAILURE() << "--keep-best-val without --stop-on-val was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--stop-on-val"), std::string::npos) << e.what();
  }
}

// --grow-on-val: with a tolerance nothing reaches, the second evaluation (20) is the first without
// a gain, so densification from 20 on (it comes after that iteration's evaluation) keeps the
// count at or under the count at 20, where the same run without it grows on. An interrupted
// run freezes at the same count (the val curve keeps it); without --stop-on-val or with
// --reference it is refused.
TEST(TrainerSpeedOptions, GrowOnValFreezesTheCountAtTheFirstValEvaluationWithoutGain) {
  TempDir dir;
  MakeTinySceneWithVal(dir / "scene");
  const auto run = StopOnValRunsWith(dir.path(), &OptimizationOptions::grow_on_val);
  const auto [a, r] = TrainToTheValStop(dir, run);
  const nlohmann::json& curve = r.at("val_curve");
  ASSERT_EQ(curve.size(), 4u);
  const auto frozen = curve[1].at("gaussians").get<std::size_t>();
  EXPECT_EQ(r.at("growth_stopped").at("iteration"), 20);
  EXPECT_EQ(r.at("growth_stopped").at("gaussians"), frozen);
  for (std::size_t i = 2; i < curve.size(); ++i)
    EXPECT_LE(curve[i].at("gaussians").get<std::size_t>(), frozen) << i;
  EXPECT_LE(a.gaussians, frozen);
  // Without it the model grows past that count (the same run up to iteration 20).
  TrainOptions free_growth = run("free", 400);
  free_growth.optimization.grow_on_val = false;
  const TrainSummary f = Train(free_growth);
  const nlohmann::json free_curve = ReadJsonFile(dir / "free" / "results.json").at("val_curve");
  EXPECT_EQ(free_curve[1].at("gaussians").get<std::size_t>(), frozen);
  EXPECT_GT(f.gaussians, frozen);
  EXPECT_FALSE(ReadJsonFile(dir / "free" / "results.json").contains("growth_stopped"));
  // Interrupted after the freeze and resumed: the same state.
  const TrainSummary b = InterruptAndResume(run, "b", 25, 400);
  EXPECT_EQ(b.loss_curve, a.loss_curve);
  ExpectSameState(dir / "b", dir / "a");
  // Refused without the val evaluations, and with --reference.
  TrainOptions no_val = run("c", 400);
  no_val.optimization.stop_on_val = false;
  const std::string message = testing::ErrorOf([&] { Train(no_val); });
  EXPECT_NE(message.find("--grow-on-val"), std::string::npos) << message;
  TrainOptions reference = run("d", 400);
  reference.reference = true;
  reference.optimization.stop_window = 0;
  reference.optimization.stop_on_val = false;
  EXPECT_NE(reference.Validate().find("--grow-on-val"), std::string::npos);
}

// stop_on_val_where_split (`hdr4d train` without a run length): a scene with a val split trains
// as --iterations auto --stop-on-val and records it so; one without trains as asked.
TEST(TrainerSpeedOptions, NoRunLengthAskedStopsOnTheValSplitWhereThereIsOne) {
  TempDir dir;
  MakeTinyScene(dir / "scene");
  auto run = [&](const char* name) {
    TrainOptions o = TinyRun(dir / "scene", dir / name, 30);
    o.stop_on_val_where_split = true;
    EXPECT_EQ(Train(o).iterations, 30);
    return std::pair{ReadJsonFile(dir / name / "config.json")["optimization"],
                     ReadJsonFile(dir / name / "results.json")};
  };
  const auto [plain_config, plain_results] = run("plain");
  EXPECT_EQ(plain_config["stop_on_val"], false);
  EXPECT_EQ(plain_config["stop_window"], 0);
  EXPECT_FALSE(plain_results.contains("stopped"));
  fs::copy_file(dir / "scene" / "transforms_test.json", dir / "scene" / "transforms_val.json");
  const auto [val_config, val_results] = run("val");
  EXPECT_EQ(val_config["stop_on_val"], true);
  EXPECT_EQ(val_config["stop_window"], OptimizationOptions::kDefaultStopWindow);
  EXPECT_EQ(val_results.at("stopped").at("window"), OptimizationOptions::kDefaultStopWindow);
  EXPECT_TRUE(val_results.at("val_curve").empty());  // 30 iterations: no evaluation yet
  // Resumed with --no-stop-on-val --stop-window 0: it trains on to the iterations asked for.
  TrainOptions resumed = TinyRun(dir / "scene", dir / "val", 45);
  resumed.resume = true;
  EXPECT_EQ(Train(resumed).iterations, 45);
  EXPECT_EQ(ReadJsonFile(dir / "val" / "config.json")["optimization"]["stop_on_val"], false);
  // A val image whose header reads but whose pixels do not (a truncated copy): the error names
  // it and says why it was read. (A missing one is refused when the scene is read, as before.)
  nlohmann::json val = ReadJsonFile(dir / "scene" / "transforms_val.json");
  const fs::path image = dir / "scene" / val["frames"][0]["file_path"].get<std::string>();
  fs::copy_file(image, dir / "scene" / "broken_view.png");
  fs::resize_file(dir / "scene" / "broken_view.png", fs::file_size(image) / 2);
  val["frames"][0]["file_path"] = "broken_view.png";
  WriteJsonFile(dir / "scene" / "transforms_val.json", val);
  TrainOptions o = TinyRun(dir / "scene", dir / "broken", 30);
  o.stop_on_val_where_split = true;
  const std::string message = testing::ErrorOf([&] { Train(o); });
  EXPECT_NE(message.find("broken_view.png"), std::string::npos) << message;
  EXPECT_NE(message.find("--iterations N trains N"), std::string::npos) << message;
}

// --test-every: each held-out evaluation records the training seconds spent so far (evaluation
// time excluded), so time to quality can be read from one run's curve.
TEST(TrainerSpeedOptions, TestCurveRecordsTheTrainingSecondsOfEachEvaluation) {
  TempDir dir;
  MakeTinyScene(dir / "scene");
  TrainOptions o = TinyRun(dir / "scene", dir / "run", 60);
  o.test_every = 20;
  Train(o);
  const nlohmann::json r = ReadJsonFile(dir / "run" / "results.json");
  const nlohmann::json& curve = r["test_curve"];
  ASSERT_EQ(curve.size(), 3u);  // 20, 40 and the end
  double before = 0;
  for (std::size_t i = 0; i < curve.size(); ++i) {
    EXPECT_EQ(curve[i]["iteration"], 20 * static_cast<int>(i + 1));
    const double s = curve[i].at("train_seconds").get<double>();
    EXPECT_GT(s, before) << "evaluation " << i;
    before = s;
    EXPECT_TRUE(curve[i].contains("psnr"));
  }
  EXPECT_DOUBLE_EQ(curve.back().at("train_seconds").get<double>(),
                   r.at("train_seconds").get<double>());
}

// Each point's seconds leave out its own evaluation too: 24 held-out views cost several training
// steps of one view each, so a point read after its evaluation would come out later than the
// end of the run's next step (the last point, the run's own training seconds).
TEST(TrainerSpeedOptions, TestCurveSecondsLeaveOutTheirOwnEvaluation) {
  TempDir dir;
  GaussianSceneOptions s;
  s.size = 48;
  s.num_gaussians = 12;
  s.num_cameras = 4;  // every 4th held out: one test camera
  s.num_timestamps = 24;
  MakeGaussianScene(s, dir / "scene");
  TrainOptions o = TinyRun(dir / "scene", dir / "run", 12);
  o.test_every = 1;
  Train(o);
  const nlohmann::json r = ReadJsonFile(dir / "run" / "results.json");
  ASSERT_EQ(r.at("test_views").get<int>(), 24);
  const nlohmann::json& curve = r["test_curve"];
  ASSERT_EQ(curve.size(), 12u);
  for (std::size_t i = 1; i < curve.size(); ++i) {
    EXPECT_LT(curve[i - 1].at("train_seconds").get<double>(),
              curve[i].at("train_seconds").get<double>())
        << "iteration " << curve[i]["iteration"];
  }
}

// The held-out views are scored before that iteration's densification, as the reference's
// training_report: the tiny run first densifies at 20, and its test curve reads there the model
// before it (as many Gaussians as a run that never densifies). A val stop is checked in
// StopOnValStopsOnTheValSplitAndResumes.
TEST(TrainerSpeedOptions, HeldOutReadingsComeBeforeTheIterationsDensification) {
  TempDir dir;
  MakeTinyScene(dir / "scene");
  auto run = [&](const char* name, int densify_until) {
    TrainOptions o = TinyRun(dir / "scene", dir / name, 60);
    o.test_every = 20;
    o.optimization.densify_until = densify_until;
    const TrainSummary s = Train(o);
    return std::pair{s, ReadJsonFile(dir / name / "results.json")};
  };
  const auto [a, ra] = run("a", 50);
  const auto [never, rn] = run("never", 20);  // densifies never: 20 is not < 20
  EXPECT_NE(a.gaussians, never.gaussians);
  const nlohmann::json& at_20 = ra["test_curve"][0];
  ASSERT_EQ(at_20["iteration"], 20);
  EXPECT_EQ(at_20["gaussians"].get<std::size_t>(), never.gaussians);
  EXPECT_NE(ra["test_curve"][1]["gaussians"].get<std::size_t>(), never.gaussians);
}

// --color-bands-by-need: a probe renders the next band at zero and never steps it, so a run whose
// probes all fail trains exactly as one that never adds a band; a threshold of 0 takes every
// band, one probe after the reference would; a run interrupted mid-probe resumes bit for bit.
TEST(TrainerSpeedOptions, ColorBandProbesDoNotChangeTrainingAndResumeExactly) {
  TempDir dir;
  MakeTinyScene(dir / "scene");
  auto run = [&](const char* name, int iterations, double signal) {
    TrainOptions o = TinyRun(dir / "scene", dir / name, iterations);
    o.optimization.color_bands_by_need = true;
    o.optimization.color_band_signal = signal;
    return o;
  };
  TrainOptions dc = TinyRun(dir / "scene", dir / "dc", 60);
  dc.optimization.sh_increase_interval = 1000000;  // the DC term alone, no probe
  const TrainSummary only_dc = Train(dc);
  const TrainSummary frozen = Train(run("frozen", 60, 1e9));
  EXPECT_EQ(frozen.loss_curve, only_dc.loss_curve);
  ExpectSameState(dir / "frozen", dir / "dc");
  const nlohmann::json bands = ReadJsonFile(dir / "frozen" / "results.json")["color_bands"];
  EXPECT_EQ(bands["sh_degree"], 0);
  ASSERT_EQ(bands["decisions"].size(), 5u);  // probes from 11, 21, ..., 51, each of SH degree 1
  for (const nlohmann::json& d : bands["decisions"]) {
    EXPECT_EQ(d["sh_degree"], 1);
    EXPECT_FALSE(d["switched_on"].get<bool>());
    EXPECT_GT(d["signal"].get<double>(), 0.0);
  }

  const TrainSummary straight = Train(run("straight", 60, 0.0));
  EXPECT_NE(straight.loss_curve, only_dc.loss_curve);
  const nlohmann::json on = ReadJsonFile(dir / "straight" / "results.json")["color_bands"];
  EXPECT_EQ(on["sh_degree"], 3);
  EXPECT_EQ(on["time_degree"], 2);
  // Split in the probe of SH degree 3 (iterations 31-40), its sums in the checkpoint.
  ExpectResumesExactly([&](const char* name, int it) { return run(name, it, 0.0); }, 37,
                       straight, dir.path());
}

// The probe sees a scene whose colours change with the view: made from Gaussians with SH degree
// 3 colours, SH degree 1 is switched on, with a larger signal at the second probe than the same
// Gaussians with one colour each give (the first, from iteration 101, comes while the DC terms
// are still far from their values).
TEST(TrainerSpeedOptions, ColorBandsSwitchOnWhereColoursFollowTheView) {
  TempDir dir;
  double second_signal[2] = {0, 0};
  for (int degree : {0, 3}) {
    const fs::path scene = dir / ("scene" + std::to_string(degree));
    GaussianSceneOptions s;
    s.size = 32;
    s.num_gaussians = 60;
    s.num_cameras = 12;
    s.num_timestamps = 3;
    s.sh_degree = degree;
    MakeGaussianScene(s, scene);
    TrainOptions o = TinyRun(scene, dir / ("run" + std::to_string(degree)), 300);
    o.optimization.color_bands_by_need = true;
    o.optimization.sh_increase_interval = 100;  // probes of 100 iterations from 101 and 201
    o.optimization.densify_until = 40;
    Train(o);
    const nlohmann::json bands =
        ReadJsonFile(dir / ("run" + std::to_string(degree)) / "results.json")["color_bands"];
    ASSERT_EQ(bands["decisions"].size(), 2u);
    EXPECT_EQ(bands["decisions"][0]["sh_degree"], 1);
    second_signal[degree == 3] = bands["decisions"][1]["signal"].get<double>();
    if (degree == 3) {
      EXPECT_GE(bands["sh_degree"].get<int>(), 1);
    }
  }
  EXPECT_GT(second_signal[1], second_signal[0]);
}

// --coarse-to-fine 40 on MakeTinyScene(size)'s views differs from a full-size run from the first
// step, and a run interrupted inside the coarse part resumes bit for bit.
void ExpectCoarseToFineChangesTheRunAndResumes(int size) {
  TempDir dir;
  MakeTinyScene(dir / "scene", size);
  auto run = [&](const char* name, int iterations, int coarse) {
    TrainOptions o = TinyRun(dir / "scene", dir / name, iterations);
    o.optimization.coarse_to_fine = coarse;
    return o;
  };
  const TrainSummary full = Train(run("full", 60, 0));
  const TrainSummary straight = Train(run("straight", 60, 40));
  ASSERT_EQ(straight.loss_curve.size(), 60u);
  EXPECT_NE(full.loss_curve[0], straight.loss_curve[0]);
  for (double loss : straight.loss_curve) EXPECT_TRUE(std::isfinite(loss));
  EXPECT_EQ(ReadJsonFile(dir / "straight" / "config.json")["optimization"]["coarse_to_fine"], 40);
  ExpectResumesExactly([&](const char* name, int it) { return run(name, it, 40); }, 27,
                       straight, dir.path());
}

// The tiny scene's 24 px: 6 px up to iteration 20, 12 px up to 40.
TEST(TrainerSpeedOptions, CoarseToFineDiffersFromFullSizeAndResumesExactly) {
  ExpectCoarseToFineChangesTheRunAndResumes(24);
}

// A size 2 and 4 do not divide (23 px): 5 px, then 11 px, the last rows and columns left out.
TEST(TrainerSpeedOptions, CoarseToFineReducesViewsOfAnySize) {
  ExpectCoarseToFineChangesTheRunAndResumes(23);
}

// --prune-contribution removes Gaussians the plain run keeps, and its statistics (the largest
// blending weights since the last densification) travel in the checkpoint: a run interrupted
// between two densifications resumes bit for bit.
TEST(TrainerSpeedOptions, PruneContributionPrunesMoreAndResumesExactly) {
  TempDir dir;
  MakeTinyScene(dir / "scene");
  auto run = [&](const char* name, int iterations, double threshold) {
    TrainOptions o = TinyRun(dir / "scene", dir / name, iterations);
    o.optimization.prune_contribution = threshold;
    return o;
  };
  Train(run("plain", 60, 0.0));
  const TrainSummary straight = Train(run("straight", 60, 0.05));
  const std::size_t plain_count = LoadCheckpoint(dir / "plain" / "checkpoint.bin").model.size();
  const std::size_t pruned_count =
      LoadCheckpoint(dir / "straight" / "checkpoint.bin").model.size();
  EXPECT_LT(pruned_count, plain_count);
  EXPECT_GT(pruned_count, 0u);
  EXPECT_EQ(ReadJsonFile(dir / "straight" / "config.json")["optimization"]["prune_contribution"],
            0.05);
  ExpectResumesExactly([&](const char* name, int it) { return run(name, it, 0.05); }, 27,
                       straight, dir.path());
  // --reference refuses it.
  TrainOptions both = run("both", 60, 0.05);
  both.reference = true;
  EXPECT_NE(both.Validate(), "");
}

// --prune-radiance-share on an HDR-4DGS run: the statistic becomes the largest share of a pixel
// (never below the weight), so it prunes another set than the weights alone; it is recorded,
// resumes bit for bit, needs --prune-contribution, and a run with LDR colours refuses it.
TEST(TrainerSpeedOptions, PruneRadianceShareChangesWhatIsPrunedAndResumesExactly) {
  TempDir dir;
  train_testing::MakeTinyHdrScene(dir / "scene", 16);
  auto run = [&](const char* name, int iterations, bool share) {
    TrainOptions o = TinyRun(dir / "scene", dir / name, iterations);
    o.hdr.method = "hdr4dgs";
    o.hdr.color_mode = ColorMode::kLogHdr;
    o.hdr.tone_mapper = ToneMapperConfig{};
    o.hdr.tone_mapper->context_window = 2;
    o.optimization.prune_contribution = 0.05;
    o.optimization.prune_radiance_share = share;
    return o;
  };
  Train(run("weights", 60, false));
  const TrainSummary straight = Train(run("straight", 60, true));
  const Checkpoint weights = LoadCheckpoint(dir / "weights" / "checkpoint.bin");
  const Checkpoint shares = LoadCheckpoint(dir / "straight" / "checkpoint.bin");
  EXPECT_NE(weights.model.xyz, shares.model.xyz);
  EXPECT_GT(shares.model.size(), 0u);
  EXPECT_EQ(ReadJsonFile(dir / "straight" / "config.json")["optimization"]
                        ["prune_radiance_share"],
            true);
  ExpectResumesExactly([&](const char* name, int it) { return run(name, it, true); }, 27,
                       straight, dir.path());
  TrainOptions alone = run("alone", 60, true);
  alone.optimization.prune_contribution = 0;
  EXPECT_NE(alone.Validate().find("give --prune-contribution"), std::string::npos)
      << alone.Validate();
  TrainOptions ldr = TinyRun(dir / "scene", dir / "ldr", 60);
  ldr.optimization.prune_contribution = 0.05;
  ldr.optimization.prune_radiance_share = true;
  EXPECT_NE(hdr4d::testing::ErrorOf([&] { Train(ldr); }).find("carry LDR colours"),
            std::string::npos);
}


// --clone-opacity-correction changes what a densification leaves (some Gaussian's opacity differs
// from the plain run's once a clone was made), is recorded, and resumes bit for bit.
TEST(TrainerSpeedOptions, CloneOpacityCorrectionChangesTheRunAndResumesExactly) {
  TempDir dir;
  MakeTinyScene(dir / "scene");
  const auto run = TinyRunsWith(dir, [](TrainOptions& o, bool correct) {
    o.optimization.clone_opacity_correction = correct;
    o.optimization.percent_dense = 1.0;  // every candidate is cloned, none split
  });
  const TrainSummary plain = Train(run("plain", 60, false));
  const TrainSummary straight = Train(run("straight", 60, true));
  EXPECT_NE(plain.loss_curve.back(), straight.loss_curve.back());
  for (double loss : straight.loss_curve) EXPECT_TRUE(std::isfinite(loss));
  EXPECT_EQ(ReadJsonFile(dir / "straight" / "config.json")["optimization"]
                        ["clone_opacity_correction"],
            true);
  ExpectResumesExactly([&](const char* name, int it) { return run(name, it, true); }, 27,
                       straight, dir.path());
}

// The colour schedule and the clone correction, left unset, are the reference's on every scene,
// a static ring of 18 training cameras (15 degrees apart) too: the many-view rule of 2026-12-06
// gave it 500 and on, and is withdrawn. Given values are recorded as given. A run recorded with
// 500 / on (by that rule) resumes on them; a record from before the correction resumes as off.
TEST(TrainerSpeedOptions, ColourScheduleIsTheReferencesUnlessGivenAndResumesAsRecorded) {
  TempDir dir;
  GaussianSceneOptions ring;
  ring.size = 16;
  ring.num_gaussians = 8;
  ring.num_cameras = 24;  // every 4th held out
  ring.num_timestamps = 2;
  MakeGaussianScene(ring, dir / "dynamic-ring");
  fs::copy(dir / "dynamic-ring", dir / "ring", fs::copy_options::recursive);
  train_testing::MakeStatic(dir / "ring");  // the same frames, all at time 0
  using Schedule = std::pair<int, bool>;
  const auto recorded = [&](const char* name) {
    const nlohmann::json o = ReadJsonFile(dir / name / "config.json")["optimization"];
    return Schedule(o["sh_increase_interval"].get<int>(),
                    o["clone_opacity_correction"].get<bool>());
  };
  const auto options = [&](const char* scene, const char* name, int iterations) {
    TrainOptions o = TinyRun(dir / scene, dir / name, iterations);
    o.optimization.sh_increase_interval = kFollowRunLength;  // unset, as on the command line
    return o;
  };
  Train(options("ring", "static", 5));
  EXPECT_EQ(recorded("static"), Schedule(1000, false));
  Train(options("dynamic-ring", "dynamic", 5));
  EXPECT_EQ(recorded("dynamic"), Schedule(1000, false));
  TrainOptions given = options("ring", "given", 5);
  given.optimization.sh_increase_interval = 500;
  given.optimization.clone_opacity_correction = true;
  Train(given);
  EXPECT_EQ(recorded("given"), Schedule(500, true));
  // Resumed with nothing given, each run keeps what it recorded.
  TrainOptions again = options("ring", "given", 8);
  again.resume = true;
  Train(again);
  EXPECT_EQ(recorded("given"), Schedule(500, true));
  nlohmann::json old = ReadJsonFile(dir / "static" / "config.json");
  old["optimization"].erase("clone_opacity_correction");
  WriteJsonFile(dir / "static" / "config.json", old);
  TrainOptions resumed = options("ring", "static", 8);
  resumed.resume = true;
  Train(resumed);
  EXPECT_EQ(recorded("static"), Schedule(1000, false));
}
}  // namespace
}  // namespace hdr4d::method
