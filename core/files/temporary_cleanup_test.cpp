#include "core/files/temporary_cleanup.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "core/files/atomic_file.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;

// Issue 51, case 19: SIGHUP (like SIGTERM and SIGINT) in the middle of a write left its
// temporary file. The child is stopped inside WriteFileAtomic's writer; its temporary goes, the
// file it was replacing keeps its bytes, and the exit status still names the signal.
TEST(TemporaryCleanup, StopSignalsRemoveTheTemporaryOfAWriteInFlight) {
  for (const int sig : {SIGHUP, SIGTERM, SIGINT}) {
    testing::TempDir dir;
    testing::WriteTextFile(dir / "checkpoint.bin", "old");
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      RemoveTemporariesOnStopSignals();
      WriteFileAtomic(dir / "checkpoint.bin", [&](std::ostream& out) {
        out << "half" << std::flush;
        ::raise(sig);
      });
      _exit(0);
    }
    int status = 0;
    ASSERT_EQ(waitpid(child, &status, 0), child);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << sig << " " << status;
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir.path())) names.push_back(e.path().filename());
    EXPECT_EQ(names, std::vector<std::string>{"checkpoint.bin"}) << sig;
    EXPECT_EQ(testing::ReadTextFile(dir / "checkpoint.bin"), "old");
  }
}

// Stop 94's sweep: a video's frames wait in one FileBatch until its commit, and a stop signal left
// every temporary beyond the 256 fixed slots (1592 of them). All are tracked now, and the nodes
// released by an earlier batch are taken again.
TEST(TemporaryCleanup, AStopSignalRemovesEveryTemporaryOfABatchBeyondTheFixedSlots) {
  testing::TempDir dir;
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    RemoveTemporariesOnStopSignals();
    {
      FileBatch earlier;
      for (int i = 0; i < 300; ++i)
        earlier.Write(dir / ("old_" + std::to_string(i)), [](const fs::path& tmp) {
          std::ofstream(tmp) << "x";
        });
    }  // not committed: removed, the nodes released
    FileBatch batch;
    for (int i = 0; i < 600; ++i)
      batch.Write(dir / ("frame_" + std::to_string(i) + ".png"), [](const fs::path& tmp) {
        std::ofstream(tmp) << "frame";
      });
    ::raise(SIGTERM);
    _exit(0);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << status;
  int left = 0;
  for (const auto& e : fs::directory_iterator(dir.path())) {
    ++left;
    ADD_FAILURE() << "left behind: " << e.path().filename();
    if (left > 3) break;
  }
  EXPECT_EQ(left, 0);
}

}  // namespace
}  // namespace hdr4d
