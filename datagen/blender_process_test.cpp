#include "datagen/blender_process.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <thread>

#include "tests/testing.h"

namespace hdr4d::datagen {
namespace {

using testing::ErrorOf;
using testing::TempDir;

// Sets an environment variable for one test and restores it afterwards.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (old_)
      setenv(name_, old_->c_str(), 1);
    else
      unsetenv(name_);
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

std::filesystem::path WriteScript(const std::filesystem::path& path, const std::string& body) {
  testing::WriteTextFile(path, "#!/bin/sh\n" + body);
  chmod(path.c_str(), 0755);
  return path;
}

TEST(BlenderProcess, StreamsLinesAndReportsTheExitCode) {
  TempDir dir;
  const auto script = WriteScript(dir / "talk.sh", "echo one\necho two >&2\nprintf tail\nexit 3\n");
  std::vector<std::string> lines;
  const ProcessResult r =
      RunProcess({script.string()}, [&](const std::string& l) { lines.push_back(l); });
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.Describe(), "exit code 3");
  EXPECT_EQ(lines, (std::vector<std::string>{"one", "two", "tail"}));
}

TEST(BlenderProcess, PassesArgumentsVerbatimAndReportsSignals) {
  TempDir dir;
  const auto echo = WriteScript(dir / "echo.sh", "for a in \"$@\"; do echo \"[$a]\"; done\n");
  std::vector<std::string> lines;
  const ProcessResult ok = RunProcess({echo.string(), "a b", "'q'", ""},
                                      [&](const std::string& l) { lines.push_back(l); });
  EXPECT_TRUE(ok.ok());
  EXPECT_EQ(lines, (std::vector<std::string>{"[a b]", "['q']", "[]"}));
  const auto killer = WriteScript(dir / "kill.sh", "kill -9 $$\n");
  const ProcessResult killed = RunProcess({killer.string()}, [](const std::string&) {});
  EXPECT_EQ(killed.signal, 9);
  EXPECT_EQ(killed.Describe(), "signal 9");
}

TEST(BlenderProcess, AThrowingCallbackStopsTheChildAndPropagates) {
  TempDir dir;
  const auto chatty = WriteScript(dir / "chatty.sh", "echo first\nsleep 30\necho never\n");
  EXPECT_THROW(RunProcess({chatty.string()}, [](const std::string&) { throw Error("stop"); }),
               Error);
}

// The pid a script wrote to `file` (waiting up to 10 s for it), or -1.
pid_t WaitForPid(const std::filesystem::path& file) {
  for (int i = 0; i < 1000; ++i) {
    std::ifstream in(file);
    pid_t pid = -1;
    if (in >> pid && pid > 0) return pid;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return -1;
}

// True once `pid` has gone (or is a zombie nobody reaped yet), waiting up to 10 s.
bool Gone(pid_t pid) {
  for (int i = 0; i < 1000; ++i) {
    std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
    std::string skip, state;
    if (!(stat >> skip >> skip >> state) || state == "Z") return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

// SIGTERM or SIGINT to hdr4d alone (not its process group) stops a Blender that prints nothing,
// and the run fails saying so instead of leaving Blender rendering.
TEST(BlenderProcess, AStopSignalToHdr4dStopsTheChild) {
  for (const int sig : {SIGTERM, SIGINT}) {
    TempDir dir;
    const auto quiet = WriteScript(dir / "quiet.sh", "echo $$ > '" + (dir / "pid").string() +
                                                         "'\nexec sleep 60\n");
    std::thread sender([&] {
      if (WaitForPid(dir / "pid") > 0) kill(getpid(), sig);
    });
    const std::string error =
        ErrorOf([&] { RunProcess({quiet.string()}, [](const std::string&) {}); });
    sender.join();
    EXPECT_NE(error.find(fmt::format("interrupted by SIG{} while", sigabbrev_np(sig))),
              std::string::npos) << error;
    EXPECT_NE(error.find("quiet.sh ran; it was stopped"), std::string::npos) << error;
    EXPECT_TRUE(Gone(WaitForPid(dir / "pid")));
  }
}

// hdr4d killed outright (no handler runs): the child gets SIGKILL through PR_SET_PDEATHSIG.
TEST(BlenderProcess, TheChildDiesWithHdr4d) {
  TempDir dir;
  const auto quiet = WriteScript(dir / "quiet.sh", "echo $$ > '" + (dir / "pid").string() +
                                                       "'\nexec sleep 60\n");
  const pid_t hdr4d = fork();
  ASSERT_GE(hdr4d, 0);
  if (hdr4d == 0) {
    try {
      RunProcess({quiet.string()}, [](const std::string&) {});
    } catch (...) {
    }
    _exit(0);
  }
  const pid_t blender = WaitForPid(dir / "pid");
  ASSERT_GT(blender, 0);
  kill(hdr4d, SIGKILL);
  int status = 0;
  waitpid(hdr4d, &status, 0);
  EXPECT_TRUE(Gone(blender));
  if (!Gone(blender)) kill(blender, SIGKILL);
}

TEST(BlenderProcess, UnstartableProgramIsAnError) {
  TempDir dir;
  const std::string error =
      ErrorOf([&] { RunProcess({(dir / "missing").string()}, [](const std::string&) {}); });
  EXPECT_NE(error.find("missing: cannot run"), std::string::npos) << error;
}

TEST(BlenderProcess, FindBlenderPrefersTheExplicitPathThenTheEnvironment) {
  TempDir dir;
  const auto fake = WriteScript(dir / "my-blender", "exit 0\n");
  EXPECT_EQ(FindBlender(fake.string()), fake);
  ScopedEnv env("HDR4D_BLENDER", fake.string());
  EXPECT_EQ(FindBlender(), fake);
}

TEST(BlenderProcess, MissingBlenderSaysHowToInstallIt) {
  TempDir dir;
  const std::string explicit_error = ErrorOf([&] { FindBlender((dir / "nope").string()); });
  EXPECT_NE(explicit_error.find("nope: Blender not found"), std::string::npos) << explicit_error;
  EXPECT_NE(explicit_error.find("--blender"), std::string::npos) << explicit_error;
  // A file that is not executable is not a Blender either.
  testing::WriteTextFile(dir / "plain", "x");
  EXPECT_NE(ErrorOf([&] { FindBlender((dir / "plain").string()); }).find("not executable"),
            std::string::npos);
  ScopedEnv path("PATH", dir.path().string());
  ScopedEnv no_env("HDR4D_BLENDER", "");
  const std::string search_error = ErrorOf([] { FindBlender(); });
  EXPECT_NE(search_error.find("not found on PATH"), std::string::npos) << search_error;
  EXPECT_NE(search_error.find("install-deps.sh"), std::string::npos) << search_error;
}

TEST(BlenderProcess, ScriptsFolderDefaultsToTheSourceTree) {
  EXPECT_TRUE(std::filesystem::exists(FindScriptsDir() / kRenderScript));
  TempDir dir;
  const std::string error = ErrorOf([&] { FindScriptsDir(dir.path().string()); });
  EXPECT_NE(error.find("render_scene.py"), std::string::npos) << error;
  EXPECT_NE(error.find("--scripts-dir"), std::string::npos) << error;
  testing::WriteTextFile(dir / kRenderScript, "pass\n");
  ScopedEnv env("HDR4D_DATAGEN_DIR", dir.path().string());
  EXPECT_EQ(FindScriptsDir(), std::filesystem::absolute(dir.path()));
}

}  // namespace
}  // namespace hdr4d::datagen
