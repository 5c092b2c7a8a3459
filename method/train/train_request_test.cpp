#include "method/train/train_request.h"

#include <gtest/gtest.h>

#include <fstream>

#include <string>

#include "core/files/json_util.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {

using nlohmann::json;
using testing::ErrorOf;

// Two methods as baselines/ defines them, without linking it: one with a tone mapper, one
// without.
HdrTrainingOptions Preset(const std::string& method) {
  HdrTrainingOptions o;
  o.method = method;
  if (method == "hdr4dgs") {
    o.color_mode = ColorMode::kLogHdr;
    o.tone_mapper = ToneMapperConfig{};
  } else {
    o.supervision = Supervision::kLdr;
  }
  return o;
}

TrainRequest Request(const std::vector<std::pair<std::string, json>>& given) {
  TrainRequest r;
  r.out = "/runs/a";
  for (const auto& [flag, value] : given) {
    const TrainOption* option = FindTrainOption(flag);
    EXPECT_NE(option, nullptr) << flag;
    r.given.push_back({option, value});
  }
  return r;
}

TEST(TrainRequest, GivenOptionsLieOverTheConfigurationOverTheDefaults) {
  TrainRequest r = Request({{"--data", "/scene"}, {"--iterations", 300}, {"--hdr-weight", 0.25f},
                            {"--context-window", 7}, {"--color-lr", 0.01}});
  r.config = "real/bed";  // iterations 20000, resolution 4, batch 4, ...
  const TrainOptions o = ResolveTrainRequest(r, Preset);
  EXPECT_EQ(o.data, "/scene");
  EXPECT_EQ(o.out, "/runs/a");
  EXPECT_EQ(o.optimization.iterations, 300);
  EXPECT_EQ(o.resolution, 4);
  EXPECT_DOUBLE_EQ(o.optimization.position_lr_init, 0.0016);
  EXPECT_EQ(o.hdr.method, "hdr4dgs");
  EXPECT_EQ(o.hdr.hdr_weight, 0.25f);
  EXPECT_EQ(o.hdr.tone_mapper->context_window, 7);
  EXPECT_EQ(o.optimization.f_dc_lr, 0.01);
  EXPECT_EQ(o.optimization.f_dc_lr_log_hdr, 0.01);
  EXPECT_FALSE(o.when_nothing_hdr);  // the HDR options asked for HDR
  EXPECT_FALSE(o.learn_background);  // unset: the run decides
}

// No run length asked for (no --iterations, --stop-window or --stop-on-val, and none in the
// configuration): the run stops on the scene's val split where it has one. Asked for, or the
// paper's configuration: the iterations asked for.
TEST(TrainRequest, NoRunLengthAskedStopsOnAValSplitWhereTheSceneHasOne) {
  EXPECT_TRUE(ResolveTrainRequest(Request({{"--data", "/scene"}}), Preset).stop_on_val_where_split);
  for (const auto& [flag, value] : std::vector<std::pair<std::string, json>>{
           {"--iterations", 20000}, {"--iterations", "auto"}, {"--stop-window", 500},
           {"--stop-on-val", false}, {"--reference", true}}) {
    EXPECT_FALSE(ResolveTrainRequest(Request({{"--data", "/scene"}, {flag, value}}), Preset)
                     .stop_on_val_where_split)
        << flag;
  }
  TrainRequest r = Request({{"--data", "/scene"}});
  r.config = "real/bed";  // iterations 20000
  EXPECT_FALSE(ResolveTrainRequest(r, Preset).stop_on_val_where_split);
}

// The radiance bank's unwritten rows: interpolated by default, zeros under --reference (as
// before), and the two together refused.
TEST(TrainRequest, ReferenceReadsUnwrittenBankRowsAsZeros) {
  TrainRequest r = Request({{"--data", "/scene"}});
  r.method = "hdr4dgs";
  EXPECT_EQ(ResolveTrainRequest(r, Preset).hdr.tone_mapper->unseen_rows, "interpolate");
  r = Request({{"--data", "/scene"}, {"--reference", true}});
  r.method = "hdr4dgs";
  const TrainOptions reference = ResolveTrainRequest(r, Preset);
  EXPECT_EQ(reference.hdr.tone_mapper->unseen_rows, "zero");
  EXPECT_EQ(reference.Validate(), "");
  r = Request({{"--data", "/scene"}, {"--reference", true}, {"--unseen-bank-rows", "interpolate"}});
  r.method = "hdr4dgs";
  EXPECT_NE(ResolveTrainRequest(r, Preset).Validate().find("drop --unseen-bank-rows"),
            std::string::npos);
  r = Request({{"--data", "/scene"}, {"--unseen-bank-rows", "zero"}});
  r.method = "hdr4dgs";
  EXPECT_EQ(ResolveTrainRequest(r, Preset).hdr.tone_mapper->unseen_rows, "zero");
}

TEST(TrainRequest, NothingHdrAskedForFallsBackToThePlainMethodOnAPlainScene) {
  const TrainOptions o = ResolveTrainRequest(
      Request({{"--data", "/scene"}, {"--hdr-target", "scene-log"}, {"--seed", 3u}}), Preset);
  ASSERT_TRUE(o.when_nothing_hdr);
  EXPECT_EQ(o.when_nothing_hdr->method, "4dgs");
  EXPECT_EQ(o.hdr.hdr_target, HdrTarget::kSceneLog);
  EXPECT_EQ(o.seed, 3u);
}

TEST(TrainRequest, MistakesAreNamedBeforeAnythingIsRead) {
  TrainRequest r = Request({{"--data", "/scene"}, {"--context-size", 3}});
  r.method = "4dgs";
  EXPECT_NE(ErrorOf([&] { ResolveTrainRequest(r, Preset); })
                .find("--method 4dgs has no tone mapper, so tone-mapper options do not apply"),
            std::string::npos);
  r = Request({{"--data", "/scene"}, {"--hdr-head-iterations", 5}});
  EXPECT_NE(ErrorOf([&] { ResolveTrainRequest(r, Preset); })
                .find("--hdr-head-iterations needs --hdr-head"),
            std::string::npos);
  r = Request({{"--data", "/scene"}, {"--hdr-weight", 2e6}});
  EXPECT_NE(ErrorOf([&] { ResolveTrainRequest(r, Preset); })
                .find("train: --hdr-weight: expected a number in [0, 1e+06], got 2000000"),
            std::string::npos);
  r = Request({{"--iterations", 5}});
  EXPECT_NE(ErrorOf([&] { ResolveTrainRequest(r, Preset); }).find("--data is required"),
            std::string::npos);
  r.out.clear();
  EXPECT_NE(ErrorOf([&] { ResolveTrainRequest(r, Preset); }).find("--out is required"),
            std::string::npos);
}

// --resume: the run's own record, the options given over it (threads excepted: this machine's),
// and --hdr-head turning an LDR-alone run into an ldr+hdr one with a head.
TEST(TrainRequest, AResumedRunStartsFromItsRecord) {
  testing::TempDir dir;
  TrainOptions started;
  started.data = "/scene";
  started.out = dir.path();
  started.seed = 9;
  started.threads = 3;
  started.learn_background = false;
  started.hdr = Preset("hdr4dgs");
  started.hdr.supervision = Supervision::kLdr;
  started.hdr.hdr_weight = 0.5f;
  WriteJsonFile(dir / "config.json", started.ToJson());
  std::ofstream(dir / "checkpoint.bin") << "";  // a run to resume has one (read by the trainer)
  TrainRequest r = Request({{"--iterations", 40}, {"--hdr-head", true}});
  r.out = dir.path();
  r.resume = true;
  const TrainOptions o = ResolveTrainRequest(r, Preset);
  EXPECT_TRUE(o.resume);
  EXPECT_EQ(o.data, "/scene");
  EXPECT_EQ(o.seed, 9u);
  EXPECT_EQ(o.threads, 0);
  EXPECT_EQ(o.optimization.iterations, 40);
  EXPECT_EQ(o.learn_background, false);
  EXPECT_EQ(o.hdr.hdr_weight, 0.5f);
  EXPECT_TRUE(o.hdr.hdr_head);
  EXPECT_EQ(o.hdr.supervision, Supervision::kLdrHdr);
  EXPECT_FALSE(o.when_nothing_hdr);
}

}  // namespace
}  // namespace hdr4d::method
