#include "core/files/folder_lock.h"

#include <gtest/gtest.h>
#include <csignal>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "core/util/error.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;

fs::path Fresh(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("hdr4d_folder_lock_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// flock excludes between open file descriptions, so a second lock in this process is refused
// just as one from another process is, and says who holds it.
TEST(FolderLock, ASecondWriterIsRefusedAndToldTheHolder) {
  const fs::path dir = Fresh("second");
  std::optional<FolderLock> first;
  first.emplace(dir, "hdr4d train --out X");
  try {
    FolderLock second(dir, "hdr4d train --out Y");
    FAIL() << "the second lock was granted";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(dir.string()), std::string::npos) << m;
    EXPECT_NE(m.find("in use by hdr4d train --out X (pid " + std::to_string(getpid())),
              std::string::npos)
        << m;
  }
  first.reset();
  EXPECT_NO_THROW(FolderLock again(dir, "hdr4d train"));  // released with its holder
}

// A holder killed with SIGKILL leaves the file but not the lock.
TEST(FolderLock, AKilledHolderDoesNotBlockTheNextWriter) {
  const fs::path dir = Fresh("killed");
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    FolderLock lock(dir, "child");
    std::ofstream(dir / "ready") << "1";
    pause();
    _exit(0);
  }
  for (int i = 0; i < 2500 && !fs::exists(dir / "ready"); ++i) usleep(2000);
  ASSERT_TRUE(fs::exists(dir / "ready"));
  EXPECT_THROW(FolderLock probe(dir, "probe"), Error);
  kill(child, SIGKILL);
  int status = 0;
  waitpid(child, &status, 0);
  EXPECT_TRUE(fs::exists(dir / FolderLock::kFileName));
  EXPECT_NO_THROW(FolderLock next(dir, "next"));
}

TEST(FolderLock, AnUncreatableLockFileIsAnErrorNamingIt) {
  const fs::path dir = Fresh("missing") / "no" / "such";
  try {
    FolderLock lock(dir, "x");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(".hdr4d-lock"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hdr4d

namespace hdr4d {
namespace {
// Issue 51, case 19: temporary checkpoints of killed runs stayed forever, also after a completed
// resume. Taking the folder removes those of dead writers and keeps those of live ones.
TEST(FolderLock, TakingTheFolderRemovesTemporariesOfDeadWriters) {
  const fs::path dir = std::filesystem::temp_directory_path() / "hdr4d_folder_lock_stale";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const pid_t child = fork();
  if (child == 0) _exit(0);
  ASSERT_GT(child, 0);
  int status = 0;
  waitpid(child, &status, 0);  // its pid is now free
  const std::string dead = std::to_string(child), live = std::to_string(getppid());
  for (const std::string& name :
       {".checkpoint.bin.tmp-" + dead + "-0", ".results.json.tmp-" + dead + "-12",
        ".checkpoint.bin.tmp-" + live + "-1", ".checkpoint.bin.tmp-" + dead + "-x",
        "checkpoint.bin.tmp-" + dead + "-0", std::string("checkpoint.bin")}) {
    std::ofstream(dir / name) << "x";
  }
  { FolderLock lock(dir, "test"); }
  EXPECT_FALSE(fs::exists(dir / (".checkpoint.bin.tmp-" + dead + "-0")));
  EXPECT_FALSE(fs::exists(dir / (".results.json.tmp-" + dead + "-12")));
  EXPECT_TRUE(fs::exists(dir / (".checkpoint.bin.tmp-" + live + "-1")));
  EXPECT_TRUE(fs::exists(dir / (".checkpoint.bin.tmp-" + dead + "-x")));
  EXPECT_TRUE(fs::exists(dir / ("checkpoint.bin.tmp-" + dead + "-0")));
  EXPECT_TRUE(fs::exists(dir / "checkpoint.bin"));
  fs::remove_all(dir);
}

// Issue 51, case 11: a lock file planted as a symlink had its target truncated.
TEST(FolderLock, APlantedLockSymlinkIsReplacedNotFollowed) {
  const fs::path dir = std::filesystem::temp_directory_path() / "hdr4d_folder_lock_link";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "victim") << "precious";
  fs::create_symlink(dir / "victim", dir / FolderLock::kFileName);
  { FolderLock lock(dir, "test"); }
  std::ifstream in(dir / "victim");
  std::string text;
  std::getline(in, text);
  EXPECT_EQ(text, "precious");
  EXPECT_FALSE(fs::is_symlink(dir / FolderLock::kFileName));
  fs::remove_all(dir);
}
}  // namespace
}  // namespace hdr4d
