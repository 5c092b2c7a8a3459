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

}  // namespace
}  // namespace hdr4d
