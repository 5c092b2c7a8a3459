#include "method/train/checkpoint.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "core/util/error.h"
#include "method/train/initialise.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {

using hdr4d::testing::ErrorOf;
using hdr4d::testing::TempDir;

Checkpoint Sample() {
  InitOptions init;
  init.num_random_points = 50;
  init.seed = 5;
  Checkpoint c;
  c.model = InitialiseGaussians(std::nullopt, init);
  c.trainer = {{"iteration", 42}, {"rng", "1 2 3"}};
  c.extra_floats = {{1.0f, 2.0f}, {}, {3.5f}};
  c.adam_state = std::string("adam\0bytes", 10);
  return c;
}

TEST(Checkpoint, RoundTripIsExact) {
  TempDir dir;
  const Checkpoint c = Sample();
  SaveCheckpoint(dir / "ck.bin", c);
  const Checkpoint back = LoadCheckpoint(dir / "ck.bin");
  EXPECT_EQ(back.model.xyz, c.model.xyz);
  EXPECT_EQ(back.model.t, c.model.t);
  EXPECT_EQ(back.model.log_scales, c.model.log_scales);
  EXPECT_EQ(back.model.rot_left, c.model.rot_left);
  EXPECT_EQ(back.model.rot_right, c.model.rot_right);
  EXPECT_EQ(back.model.opacity_logit, c.model.opacity_logit);
  EXPECT_EQ(back.model.color_dc, c.model.color_dc);
  EXPECT_EQ(back.model.color_rest, c.model.color_rest);
  EXPECT_EQ(back.model.temporal, c.model.temporal);
  EXPECT_EQ(back.trainer, c.trainer);
  EXPECT_EQ(back.extra_floats, c.extra_floats);
  EXPECT_EQ(back.adam_state, c.adam_state);
}

// A run only looked at skips the optimiser's state: everything else as saved, and the checksum
// still covers the skipped bytes.
TEST(Checkpoint, LoadWithoutTheOptimiserStateKeepsTheRestAndTheChecks) {
  TempDir dir;
  const Checkpoint c = Sample();
  ASSERT_FALSE(c.adam_state.empty());
  SaveCheckpoint(dir / "ck.bin", c);
  const Checkpoint back = LoadCheckpoint(dir / "ck.bin", {.optimizer_state = false});
  EXPECT_TRUE(back.adam_state.empty());
  EXPECT_EQ(back.model.xyz, c.model.xyz);
  EXPECT_EQ(back.model.color_rest, c.model.color_rest);
  EXPECT_EQ(back.trainer, c.trainer);
  EXPECT_EQ(back.extra_floats, c.extra_floats);
  EXPECT_EQ(back.tone_mapper_state, c.tone_mapper_state);
  std::string bytes = testing::ReadTextFile(dir / "ck.bin");
  const std::size_t in_adam = bytes.find(c.adam_state);
  ASSERT_NE(in_adam, std::string::npos);
  bytes[in_adam + c.adam_state.size() / 2] ^= 0x01;
  testing::WriteTextFile(dir / "adam_flipped.bin", bytes);
  EXPECT_NE(ErrorOf([&] {
              LoadCheckpoint(dir / "adam_flipped.bin", {.optimizer_state = false});
            }).find("checksum mismatch"),
            std::string::npos);
}

TEST(Checkpoint, BadFilesAreErrorsNamingTheFile) {
  TempDir dir;
  EXPECT_NE(ErrorOf([&] { LoadCheckpoint(dir / "none.bin"); }).find("not found"),
            std::string::npos);
  testing::WriteTextFile(dir / "foreign.bin", "PK\x03\x04 something else entirely");
  EXPECT_NE(ErrorOf([&] { LoadCheckpoint(dir / "foreign.bin"); }).find("not an hdr4d checkpoint"),
            std::string::npos);
  SaveCheckpoint(dir / "ck.bin", Sample());
  const std::string bytes = testing::ReadTextFile(dir / "ck.bin");
  // Every truncation is reported, never a crash or a half-filled model.
  for (std::size_t cut : {std::size_t{9}, bytes.size() / 3, bytes.size() / 2, bytes.size() - 1}) {
    testing::WriteTextFile(dir / "cut.bin", bytes.substr(0, cut));
    const std::string error = ErrorOf([&] { LoadCheckpoint(dir / "cut.bin"); });
    EXPECT_NE(error.find((dir / "cut.bin").string()), std::string::npos) << cut << ": " << error;
    const std::string skipping =
        ErrorOf([&] { LoadCheckpoint(dir / "cut.bin", {.optimizer_state = false}); });
    EXPECT_NE(skipping.find((dir / "cut.bin").string()), std::string::npos) << cut;
  }
}

TEST(Checkpoint, DamagedBytesAreRefusedByTheChecksum) {
  TempDir dir;
  SaveCheckpoint(dir / "ck.bin", Sample());
  std::string bytes = testing::ReadTextFile(dir / "ck.bin");
  // One bit inside the float buffers: sizes and structure stay valid, only the checksum sees it.
  bytes[bytes.size() / 2] ^= 0x10;
  testing::WriteTextFile(dir / "flipped.bin", bytes);
  const std::string error = ErrorOf([&] { LoadCheckpoint(dir / "flipped.bin"); });
  EXPECT_NE(error.find("checksum mismatch"), std::string::npos) << error;
  EXPECT_NE(error.find("flipped.bin"), std::string::npos) << error;
}

TEST(Checkpoint, FailedSaveKeepsThePreviousCheckpoint) {
  TempDir dir;
  SaveCheckpoint(dir / "ck.bin", Sample());
  const std::string before = testing::ReadTextFile(dir / "ck.bin");
  std::filesystem::create_directory(dir / "ck.bin.dir");
  // A checkpoint path that is a folder cannot be replaced: the error names it.
  EXPECT_THROW(SaveCheckpoint(dir / "ck.bin.dir", Sample()), Error);
  EXPECT_EQ(testing::ReadTextFile(dir / "ck.bin"), before);
}

// Training saves its live model and optimiser through CheckpointParts (no copies): the file is
// byte for byte the one a Checkpoint holding the same state as bytes gives.
TEST(Checkpoint, StreamedPartsWriteTheSameBytes) {
  TempDir dir;
  Checkpoint c = Sample();
  std::vector<float> p(12, 0.5f), g(12, 0.25f);
  Adam adam;
  adam.AddGroup({"xyz", p.data(), g.data(), p.size(), 1e-3f});
  adam.Step();
  std::ostringstream adam_bytes;
  adam.Save(adam_bytes);
  c.adam_state = adam_bytes.str();
  SaveCheckpoint(dir / "copied.bin", c);
  SaveCheckpoint(dir / "streamed.bin",
                 CheckpointParts{.model = &c.model,
                                 .trainer = &c.trainer,
                                 .extra_floats = {&c.extra_floats[0], &c.extra_floats[1],
                                                  &c.extra_floats[2]},
                                 .adam_state = CheckpointSection::Of(adam),
                                 .tone_mapper_state = CheckpointSection::Of("")});
  EXPECT_EQ(testing::ReadTextFile(dir / "streamed.bin"), testing::ReadTextFile(dir / "copied.bin"));
  EXPECT_EQ(LoadCheckpoint(dir / "streamed.bin").adam_state, c.adam_state);
}

// A section that writes other than the size it announced would make an unreadable file: the
// save fails and the previous checkpoint stays.
TEST(Checkpoint, SectionOfTheWrongSizeKeepsThePreviousCheckpoint) {
  TempDir dir;
  const Checkpoint c = Sample();
  SaveCheckpoint(dir / "ck.bin", c);
  const std::string before = testing::ReadTextFile(dir / "ck.bin");
  CheckpointParts parts{.model = &c.model, .trainer = &c.trainer};
  parts.adam_state = {12, [](std::ostream& out) { out << "short"; }};
  const std::string error = ErrorOf([&] { SaveCheckpoint(dir / "ck.bin", parts); });
  EXPECT_NE(error.find("12 bytes announced, 5 written"), std::string::npos) << error;
  EXPECT_EQ(testing::ReadTextFile(dir / "ck.bin"), before);
}

}  // namespace
}  // namespace hdr4d::method
