#include "core/files/staged_folder.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/util/error.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;
using testing::TempDir;

int Entries(const fs::path& dir) {
  int n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

TEST(StagedFolder, BuildsBesideAndMovesIntoPlaceWhenCommitted) {
  TempDir dir;
  {
    StagedFolder staged(dir / "scene");
    EXPECT_FALSE(fs::exists(dir / "scene"));
    testing::WriteTextFile(staged.path() / "a.json", "{}");
    staged.Commit();
  }
  EXPECT_TRUE(fs::exists(dir / "scene" / "a.json"));
  EXPECT_EQ(Entries(dir.path()), 1);  // no staging folder left
  // An empty folder is a fine place.
  fs::create_directories(dir / "empty");
  StagedFolder staged(dir / "empty");
  testing::WriteTextFile(staged.path() / "b.json", "{}");
  staged.Commit();
  EXPECT_TRUE(fs::exists(dir / "empty" / "b.json"));
}

// Issue 11, case 4: make-demo-scene over an existing dataset overwrote part of it.
TEST(StagedFolder, RefusesAFolderThatIsNotEmpty) {
  TempDir dir;
  testing::WriteTextFile(dir / "scene" / "transforms_train.json", "{}");
  const std::string error = testing::ErrorOf([&] { StagedFolder staged(dir / "scene"); });
  EXPECT_NE(error.find("scene: exists and is not empty"), std::string::npos) << error;
  EXPECT_EQ(Entries(dir.path()), 1);
  testing::WriteTextFile(dir / "file", "x");
  EXPECT_NE(testing::ErrorOf([&] { StagedFolder staged(dir / "file"); }).find("not a folder"),
            std::string::npos);
}

TEST(StagedFolder, AFailedBuildLeavesNothing) {
  TempDir dir;
  try {
    StagedFolder staged(dir / "scene");
    testing::WriteTextFile(staged.path() / "half.json", "{");
    throw Error("the build failed");
  } catch (const Error&) {
  }
  EXPECT_EQ(Entries(dir.path()), 0);
}

// A killed build leaves its staging folder; the next build removes it (its process is gone).
TEST(StagedFolder, LeftoversOfKilledBuildsAreRemoved) {
  TempDir dir;
  const fs::path leftover = dir / ".scene.staging-999999999";  // beyond any pid
  testing::WriteTextFile(leftover / "x.exr", "half");
  const fs::path not_ours = dir / ".scene.staging-abc";
  fs::create_directories(not_ours);
  StagedFolder staged(dir / "scene");
  staged.Commit();
  EXPECT_FALSE(fs::exists(leftover));
  EXPECT_TRUE(fs::exists(not_ours));
}

}  // namespace
}  // namespace hdr4d
