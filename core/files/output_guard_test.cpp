#include "core/files/output_guard.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/files/atomic_file.h"
#include "core/util/error.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;
using testing::ErrorOf;
using testing::TempDir;

TEST(OutputGuard, AProtectedFileIsRefusedUnderEverySpelling) {
  TempDir dir;
  const InputProtectionScope scope;
  testing::WriteTextFile(dir / "gt" / "a.exr", "ground truth");
  ProtectInputFile(dir / "gt" / "a.exr", "the ground truth");
  fs::create_symlink(dir / "gt" / "a.exr", dir / "link.exr");
  fs::create_hard_link(dir / "gt" / "a.exr", dir / "hard.exr");
  for (const fs::path& p : {dir / "gt" / "a.exr", dir / "gt" / ".." / "gt" / "a.exr",
                            dir / "link.exr", dir / "hard.exr"}) {
    const std::string error = ErrorOf([&] { CheckOutput(p); });
    EXPECT_NE(error.find(p.string() + ": refusing to write: it is the ground truth"),
              std::string::npos)
        << error;
    // The writer asks the guard itself: the file keeps its content.
    EXPECT_THROW(WriteTextFileAtomic(p, "overwritten"), Error);
  }
  EXPECT_EQ(testing::ReadTextFile(dir / "gt" / "a.exr"), "ground truth");
  EXPECT_NO_THROW(CheckOutput(dir / "b.exr"));
}

// A run folder found by looking: its own files are written only by the trainer that says it owns
// the folder (eval --out RUN/checkpoint.bin replaced a trained model, sweep of stop 94).
TEST(OutputGuard, ATrainingRunsFilesAreWrittenOnlyByItsTrainer) {
  TempDir dir;
  const InputProtectionScope scope;
  testing::WriteTextFile(dir / "run" / "config.json", "{}");
  testing::WriteTextFile(dir / "run" / "checkpoint.bin", "model");
  testing::WriteTextFile(dir / "locked" / ".hdr4d-lock", "");
  for (const fs::path& p : {dir / "run" / "checkpoint.bin", dir / "run" / "config.json",
                            dir / "run" / "results.json", dir / "run" / "data_checksums.json",
                            dir / "run" / ".hdr4d-lock", dir / "locked" / "results.json"}) {
    const std::string error = ErrorOf([&] { CheckOutput(p); });
    EXPECT_NE(error.find(p.string() + ": refusing to write: it is a file of training run "),
              std::string::npos) << error;
    EXPECT_THROW(WriteTextFileAtomic(p, "eval's JSON"), Error);
  }
  EXPECT_EQ(testing::ReadTextFile(dir / "run" / "checkpoint.bin"), "model");
  // Other files of a run, and the same names in a folder that is no run, are any command's.
  EXPECT_NO_THROW(CheckOutput(dir / "run" / "eval.json"));
  testing::WriteTextFile(dir / "other" / "config.json", "{}");
  EXPECT_NO_THROW(CheckOutput(dir / "other" / "config.json"));
  {
    const RunFolderWriter trainer(dir / "run");
    EXPECT_NO_THROW(WriteTextFileAtomic(dir / "run" / "checkpoint.bin", "trained further"));
    EXPECT_THROW(CheckOutput(dir / "locked" / "results.json"), Error);  // another run
  }
  EXPECT_THROW(CheckOutput(dir / "run" / "checkpoint.bin"), Error);
}

TEST(OutputGuard, AFileThatDoesNotExistYetIsProtectedByItsPath) {
  TempDir dir;
  const InputProtectionScope scope;
  ProtectInputFile(dir / "images" / "x.png", "an image of the dataset");
  EXPECT_THROW(CheckOutput(dir / "images" / "x.png"), Error);
}

TEST(OutputGuard, NothingMayBeWrittenDirectlyInsideAProtectedFolder) {
  TempDir dir;
  const InputProtectionScope scope;
  fs::create_directories(dir / "images" / "sub");
  fs::create_symlink(dir / "images", dir / "alias");
  ProtectInputFolder(dir / "images", "the images of the dataset");
  for (const fs::path& p : {dir / "images" / "new.png", dir / "alias" / "new.png"}) {
    const std::string error = ErrorOf([&] { CheckOutput(p); });
    EXPECT_NE(error.find("refusing to write into"), std::string::npos) << error;
    EXPECT_NE(error.find("the images of the dataset"), std::string::npos) << error;
  }
  EXPECT_THROW(CheckOutputFolder(dir / "images"), Error);
  EXPECT_THROW(CheckOutputFolder(dir / "alias"), Error);
  EXPECT_NO_THROW(CheckOutput(dir / "images" / "sub" / "x.png"));  // only direct children
  EXPECT_NO_THROW(CheckOutputFolder(dir / "renders"));
}

TEST(OutputGuard, APermitLetsExactlyItsFilesThrough) {
  TempDir dir;
  const InputProtectionScope scope;
  ProtectInputFolder(dir.path(), "the dataset");
  {
    const OutputPermit permit({dir / "images_a.png"});
    EXPECT_NO_THROW(CheckOutput(dir / "images_a.png"));
    EXPECT_THROW(CheckOutput(dir / "images_b.png"), Error);
  }
  EXPECT_THROW(CheckOutput(dir / "images_a.png"), Error);  // the permit ended
}

// Registrations belong to one command: without a scope nothing is recorded, and the end of the
// scope forgets them (a long-running process runs commands one after another).
TEST(OutputGuard, RegistrationsLastAsLongAsTheScope) {
  TempDir dir;
  ProtectInputFile(dir / "a.json", "input");
  EXPECT_NO_THROW(CheckOutput(dir / "a.json"));
  {
    const InputProtectionScope scope;
    ProtectInputFile(dir / "a.json", "input");
    EXPECT_THROW(CheckOutput(dir / "a.json"), Error);
  }
  EXPECT_NO_THROW(CheckOutput(dir / "a.json"));
}

// A protected file that was replaced since (its inode now belongs to something else) does not
// make an unrelated file with a reused inode unwritable.
TEST(OutputGuard, IdentityMatchesOnlyWhileTheProtectedPathIsThatFile) {
  TempDir dir;
  const InputProtectionScope scope;
  testing::WriteTextFile(dir / "in.txt", "x");
  ProtectInputFile(dir / "in.txt", "input");
  fs::rename(dir / "in.txt", dir / "moved.txt");
  EXPECT_NO_THROW(CheckOutput(dir / "moved.txt"));
  EXPECT_THROW(CheckOutput(dir / "in.txt"), Error);  // the path itself stays protected
}

TEST(OutputGuard, SameFileSeesThroughLinks) {
  TempDir dir;
  testing::WriteTextFile(dir / "a", "x");
  fs::create_symlink(dir / "a", dir / "s");
  fs::create_hard_link(dir / "a", dir / "h");
  EXPECT_TRUE(SameFile(dir / "a", dir / "s"));
  EXPECT_TRUE(SameFile(dir / "h", dir / "s"));
  EXPECT_TRUE(SameFile(dir / "new", dir / "." / "new"));
  EXPECT_FALSE(SameFile(dir / "a", dir / "new"));
}

}  // namespace
}  // namespace hdr4d

namespace hdr4d {
namespace {
// Issue 51, case 10: `bench table --out SCENE/images` wrote among the ground truth because
// bench table reads no dataset to register. A dataset's image folders are found by looking.
TEST(OutputGuard, ADatasetsImageFoldersAreRefusedAlsoWhenNoDatasetWasRead) {
  testing::TempDir dir;
  fs::create_directories(dir / "S" / "images" / "cam0");
  fs::create_directories(dir / "S" / "hdr");
  fs::create_directories(dir / "S" / "renders");
  testing::WriteTextFile(dir / "S" / "transforms_train.json",
                         R"({"frames": [{"file_path": "images/cam0/a.png", "exr_file_path": "./hdr/a.exr"}]})");
  const InputProtectionScope scope;
  for (const fs::path& p : {dir / "S" / "images", dir / "S" / "images" / "cam0", dir / "S" / "hdr",
                            dir / "S" / "hdr" / ".." / "images"}) {
    const std::string error = testing::ErrorOf([&] { CheckOutputFolder(p); });
    EXPECT_NE(error.find("it holds the images of dataset " + (dir / "S").string()), std::string::npos)
        << p << ": " << error;
  }
  EXPECT_NO_THROW(CheckOutputFolder(dir / "S" / "renders"));
  EXPECT_NO_THROW(CheckOutputFolder(dir / "S"));
  EXPECT_NO_THROW(CheckOutputFolder(dir / "T"));
}

// The sweep of session 94: `eval --out S/images/a.png` and `synth-ldr -o S/images/a.png` replaced
// a ground-truth image; a single output file is checked against the folder it goes into.
TEST(OutputGuard, AFileNamedForOutputIsRefusedInADatasetsImageFolder) {
  testing::TempDir dir;
  fs::create_directories(dir / "S" / "images");
  fs::create_directories(dir / "S" / "hdr");
  testing::WriteTextFile(
      dir / "S" / "transforms_test.json",
      R"({"frames": [{"file_path": "images/a", "exr_file_path": "hdr/a.exr"}]})");
  testing::WriteTextFile(dir / "S" / "images" / "a.png", "truth");
  const InputProtectionScope scope;
  for (const fs::path& p : {dir / "S" / "images" / "a.png", dir / "S" / "hdr" / "res.json",
                            dir / "S" / "images" / "new.png"}) {
    EXPECT_NO_THROW(CheckOutput(p)) << p;  // what the writers of many files check
    const std::string error = testing::ErrorOf([&] { CheckOutputFile(p); });
    EXPECT_NE(error.find("it holds the images of dataset " + (dir / "S").string()),
              std::string::npos) << p << ": " << error;
  }
  EXPECT_NO_THROW(CheckOutputFile(dir / "S" / "eval.json"));
  EXPECT_NO_THROW(CheckOutputFile(dir / "T" / "eval.json"));
}

// Issue 51, case 11: only paths named on the command line are written through when they are
// symlinks; one found inside an output folder is replaced and its target keeps its bytes.
TEST(OutputGuard, OnlyNamedSymlinksAreWrittenThrough) {
  testing::TempDir dir;
  testing::WriteTextFile(dir / "victim", "precious");
  fs::create_directories(dir / "out");
  fs::create_symlink(dir / "victim", dir / "out" / "checkpoint.bin");
  fs::create_symlink(dir / "victim", dir / "named.json");
  const InputProtectionScope scope;
  NameOnCommandLine("--out=" + (dir / "named.json").string());
  NameOnCommandLine((dir / "out").string());
  WriteTextFileAtomic(dir / "out" / "checkpoint.bin", "new");
  EXPECT_FALSE(fs::is_symlink(dir / "out" / "checkpoint.bin"));
  EXPECT_EQ(testing::ReadTextFile(dir / "out" / "checkpoint.bin"), "new");
  EXPECT_EQ(testing::ReadTextFile(dir / "victim"), "precious");
  WriteTextFileAtomic(dir / "named.json", "asked for");
  EXPECT_TRUE(fs::is_symlink(dir / "named.json"));
  EXPECT_EQ(testing::ReadTextFile(dir / "victim"), "asked for");
}
}  // namespace
}  // namespace hdr4d
