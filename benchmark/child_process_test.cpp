#include "benchmark/child_process.h"

#include <gtest/gtest.h>

#include <thread>

#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
using testing::TempDir;

ChildResult Sh(const TempDir& dir, const std::string& script, double timeout = 0,
               const std::atomic<bool>* cancel = nullptr) {
  return RunChild({.argv = {"/bin/sh", "-c", script}, .log = dir / "log.txt",
                   .timeout_seconds = timeout, .cancel = cancel});
}

TEST(ChildProcess, ExitCodesSignalsAndTheErrorLine) {
  TempDir dir;
  EXPECT_TRUE(Sh(dir, "exit 0").ok());
  const ChildResult e = Sh(dir, "echo progress; echo 'hdr4d: error: scene/x.png: bad' >&2; echo after; exit 1");
  EXPECT_EQ(e.exit_code, 1);
  EXPECT_EQ(e.error_line, "hdr4d: error: scene/x.png: bad");
  EXPECT_NE(e.Describe().find("exit code 1: hdr4d: error: scene/x.png"), std::string::npos);
  const ChildResult k = Sh(dir, "kill -9 $$");
  EXPECT_EQ(k.signal, 9);
  EXPECT_FALSE(k.ok());
  // The log keeps every command and its output.
  const std::string log = testing::ReadTextFile(dir / "log.txt");
  EXPECT_NE(log.find("$ /bin/sh -c 'exit 0'"), std::string::npos) << log;
  EXPECT_NE(log.find("progress"), std::string::npos);
}

TEST(ChildProcess, AProgramThatCannotRunIsAnErrorNotAResult) {
  TempDir dir;
  const std::string e = testing::ErrorOf(
      [&] { RunChild({.argv = {(dir / "no-such-program").string()}, .log = dir / "log.txt"}); });
  EXPECT_NE(e.find("cannot execute"), std::string::npos) << e;
  EXPECT_NE(e.find("no-such-program"), std::string::npos) << e;
}

TEST(ChildProcess, TimeoutAndCancelStopTheWholeProcessGroup) {
  TempDir dir;
  const ChildResult t = Sh(dir, "sleep 30 & sleep 30; wait", 0.3);
  EXPECT_TRUE(t.timed_out);
  EXPECT_LT(t.wall_seconds, 10);
  std::atomic<bool> cancel{false};
  std::thread stop([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    cancel = true;
  });
  const ChildResult c = Sh(dir, "sleep 30", 0, &cancel);
  stop.join();
  EXPECT_TRUE(c.cancelled);
  EXPECT_EQ(c.signal, 15);
}

TEST(ChildProcess, MeasuresPeakMemory) {
  TempDir dir;
  // A shell holding a 40 MB string peaks well above an idle one.
  const ChildResult idle = Sh(dir, "true");
  const ChildResult big = Sh(dir, "x=$(head -c 40000000 /dev/zero | tr '\\0' a); echo ${#x}");
  EXPECT_GT(idle.peak_rss_mb, 0);
  EXPECT_GT(big.peak_rss_mb, idle.peak_rss_mb + 20);
}

TEST(ChildProcess, QuotingForShells) {
  EXPECT_EQ(ShellQuote("plain/path-1.json"), "plain/path-1.json");
  EXPECT_EQ(ShellQuote("it's here"), "'it'\\''s here'");
  EXPECT_EQ(ShellCommand({"a", "b c"}), "a 'b c'");
}

}  // namespace
}  // namespace hdr4d::bench
