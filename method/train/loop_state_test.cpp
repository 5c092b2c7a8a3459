// The trainer state saved in a checkpoint: the held-out curve of --stop-on-val survives the round
// trip, older checkpoints without it resume with none, and a damaged one is refused by name.
#include "method/train/loop_state.h"

#include <gtest/gtest.h>

#include <string>

#include "core/util/error.h"

namespace hdr4d::method {
namespace {

LoopState Sample() {
  LoopState s;
  s.iteration = 40;
  s.order = {2, 0, 1};
  s.next = 1;
  s.loss_curve = std::vector<double>(40, 0.1);
  s.val_curve = nlohmann::json::array(
      {{{"iteration", 20}, {"psnr", 21.5}, {"train_seconds", 1.0}},
       {{"iteration", 40}, {"psnr", nullptr}, {"train_seconds", 2.0}}});
  s.train_seconds = 2.5;
  return s;
}

TEST(LoopState, TheValCurveSurvivesTheRoundTrip) {
  LoopState back;
  back.FromJson(Sample().ToJson(), "ck.bin", 3);
  EXPECT_EQ(back.val_curve, Sample().val_curve);
  EXPECT_EQ(back.iteration, 40);
}

TEST(LoopState, ACheckpointFromBeforeTheValCurveResumesWithNone) {
  nlohmann::json j = Sample().ToJson();
  j.erase("val_curve");
  LoopState back;
  back.FromJson(j, "ck.bin", 3);
  EXPECT_TRUE(back.val_curve.is_array());
  EXPECT_TRUE(back.val_curve.empty());
}

TEST(LoopState, ADamagedValCurveIsRefusedNamingTheFile) {
  for (const nlohmann::json& bad :
       {nlohmann::json("x"), nlohmann::json::array({{{"iteration", 10}}}),
        nlohmann::json::array({{{"iteration", "ten"}, {"psnr", 20.0}}}),
        nlohmann::json::array({{{"iteration", 10}, {"psnr", "high"}}})}) {
    nlohmann::json j = Sample().ToJson();
    j["val_curve"] = bad;
    LoopState back;
    try {
      back.FromJson(j, "run/checkpoint.bin", 3);
      ADD_FAILURE() << "accepted " << bad.dump();
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("run/checkpoint.bin"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("val_curve"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace hdr4d::method
