#include "datagen/blender_process.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdlib>

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
