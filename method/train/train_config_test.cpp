#include "method/train/train_config.h"

#include <gtest/gtest.h>

#include <set>

#include "core/files/json_util.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {

const auto kNoFlags = [](const std::string&) { return false; };

TEST(TrainConfig, PresetsCarryTheReferenceSettings) {
  TrainOptions o;
  ApplyTrainConfig(ReadTrainConfig("syn/hook"), "syn/hook", kNoFlags, &o);
  EXPECT_EQ(o.optimization.iterations, 20000);
  EXPECT_EQ(o.resolution, 2);
  EXPECT_EQ(o.optimization.batch_size, 1);
  EXPECT_EQ(o.optimization.densify_until, 18000);
  EXPECT_EQ(o.optimization.position_lr_max_steps, 18000);
  EXPECT_EQ(o.optimization.densification_interval, 200);
  TrainOptions tank;
  ApplyTrainConfig(ReadTrainConfig("syn/tank"), "syn/tank", kNoFlags, &tank);
  EXPECT_EQ(tank.optimization.densification_interval, 100);
  TrainOptions real;
  ApplyTrainConfig(ReadTrainConfig("real/toys"), "real/toys", kNoFlags, &real);
  EXPECT_EQ(real.resolution, 4);
  EXPECT_EQ(real.optimization.batch_size, 4);
  EXPECT_EQ(real.optimization.densify_until, 15000);
  EXPECT_EQ(real.optimization.max_gaussians, 2'000'000);
  TrainOptions bed;
  ApplyTrainConfig(ReadTrainConfig("real/bed"), "real/bed", kNoFlags, &bed);
  EXPECT_EQ(bed.optimization.densify_until, 10000);
  EXPECT_DOUBLE_EQ(bed.optimization.position_lr_init, 0.0016);
  TrainOptions trex;
  ApplyTrainConfig(ReadTrainConfig("dnerf/trex"), "dnerf/trex", kNoFlags, &trex);
  EXPECT_EQ(trex.optimization.batch_size, 24);
  EXPECT_EQ(trex.optimization.iterations, 30000);
  // Every preset applies cleanly and names are unique.
  std::set<std::string> names;
  for (const TrainPreset& p : TrainPresets()) {
    TrainOptions any;
    ApplyTrainConfig(p.values, p.name, kNoFlags, &any);
    EXPECT_EQ(any.Validate().find("batch"), std::string::npos) << p.name;
    EXPECT_TRUE(names.insert(p.name).second) << p.name;
  }
}

TEST(TrainConfig, AGivenFlagWinsOverTheConfiguration) {
  TrainOptions o;
  o.optimization.iterations = 3000;  // as if --iterations 3000 was given
  ApplyTrainConfig(ReadTrainConfig("real/bed"), "real/bed",
                   [](const std::string& flag) { return flag == "--iterations"; }, &o);
  EXPECT_EQ(o.optimization.iterations, 3000);
  EXPECT_EQ(o.optimization.batch_size, 4);
  // Unset schedules still follow the run length.
  EXPECT_LT(o.optimization.densify_from, 0);
}

TEST(TrainConfig, FilesAndTheirErrorsNameTheFileAndKey) {
  testing::TempDir dir;
  const auto file = (dir / "mine.json").string();
  WriteJsonFile(file, {{"batch_size", 3}, {"densify_grad_threshold", 3e-4}});
  TrainOptions o;
  ApplyTrainConfig(ReadTrainConfig(file), file, kNoFlags, &o);
  EXPECT_EQ(o.optimization.batch_size, 3);
  EXPECT_DOUBLE_EQ(o.optimization.densify_grad_threshold, 3e-4);
  auto error = [&](const nlohmann::json& j) {
    return testing::ErrorOf([&] { ApplyTrainConfig(j, file, kNoFlags, &o); });
  };
  std::string m = error({{"batch_sise", 3}});
  EXPECT_NE(m.find("mine.json: unknown key 'batch_sise'"), std::string::npos) << m;
  m = error({{"batch_size", "4"}});
  EXPECT_NE(m.find("key 'batch_size': expected an integer in [1, 4096], got \"4\""),
            std::string::npos)
      << m;
  m = error({{"batch_size", 2.5}});
  EXPECT_NE(m.find("expected an integer"), std::string::npos) << m;
  m = error({{"resolution", 0}});
  // The range --resolution's help states, in the same words.
  EXPECT_NE(m.find("key 'resolution': expected an integer in [1, 65536], got 0"), std::string::npos)
      << m;
  m = error({{"densify_from", -1}});  // "follow the run length" is the default, not a value
  EXPECT_NE(m.find("key 'densify_from': expected an integer >= 0, got -1"), std::string::npos) << m;
  m = testing::ErrorOf([] { ReadTrainConfig("syn/legoo"); });
  EXPECT_NE(m.find("syn/legoo: no such file and no such preset"), std::string::npos) << m;
  EXPECT_NE(m.find("syn/lego"), std::string::npos) << m;
  WriteJsonFile(file, nlohmann::json::array({1, 2}));
  m = testing::ErrorOf([&] { ReadTrainConfig(file); });
  EXPECT_NE(m.find("mine.json: a training configuration must be a JSON object"), std::string::npos)
      << m;
}

// Issue 51 §24: `--config /dev/null` said "no such file and no such preset". Something at the
// path is the file meant: what is wrong with it is said instead.
TEST(TrainConfig, APathThatIsNoConfigurationFileSaysWhatItIs) {
  testing::TempDir dir;
  std::string m = testing::ErrorOf([] { ReadTrainConfig("/dev/null"); });
  EXPECT_NE(m.find("--config /dev/null: is a character device, expected a JSON file"),
            std::string::npos)
      << m;
  m = testing::ErrorOf([&] { ReadTrainConfig(dir.path().string()); });
  EXPECT_NE(m.find("is a folder, expected a JSON file"), std::string::npos) << m;
  const std::string empty = (dir / "empty.json").string();
  testing::WriteTextFile(empty, "");
  m = testing::ErrorOf([&] { ReadTrainConfig(empty); });
  EXPECT_NE(m.find("--config " + empty + ": the file is empty, expected a JSON object"),
            std::string::npos)
      << m;
  const std::string text = (dir / "notes.txt").string();
  testing::WriteTextFile(text, "iterations = 3\n");
  m = testing::ErrorOf([&] { ReadTrainConfig(text); });
  EXPECT_NE(m.find(text + ": invalid JSON"), std::string::npos) << m;
  EXPECT_EQ(m.find("no such"), std::string::npos) << m;
}

}  // namespace
}  // namespace hdr4d::method
