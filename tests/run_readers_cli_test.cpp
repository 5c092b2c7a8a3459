// Stop 94's sweep of the commands that read a trained run (render, export-ply, view, tone-curves,
// eval of its renders) and of `train --resume` after the run folder was edited. Each test names
// the defect it covers (D1..D12 of the sweep) and failed before its fix.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "tests/hostile_scene_fixture.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;
using testing::ReadTextFile;
using testing::RunHdr4d;

class RunReaders : public HostileScene {
 protected:
  void Train(const std::string& run, const std::string& more = "") {
    const auto r = RunHdr4d("train --data " + S() + " --out " + run +
                            " --iterations 20 --threads 1 " + more);
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  // A copy of run R with config.json edited by `edit`.
  std::string EditedCopy(const std::string& name, const std::function<void(json&)>& edit) {
    const fs::path copy = *this / name;
    fs::copy(R(), copy, fs::copy_options::recursive);
    fs::remove(copy / ".hdr4d-lock");
    json config = json::parse(ReadTextFile(copy / "config.json"));
    edit(config);
    testing::WriteTextFile(copy / "config.json", config.dump(2));
    return copy.string();
  }
};

// D1, D11: `eval --out RUN/checkpoint.bin` replaced the trained model with eval's JSON (also
// config.json, results.json); `view --out RUN/.hdr4d-lock` replaced the lock. A run's own files
// are written by its trainer only.
TEST_F(RunReaders, D01TheFilesOfARunAreNoOutputOfAnotherCommand) {
  TrainRun();
  ASSERT_EQ(RunHdr4d("render --run " + R() + " --threads 1").exit_code, 0);
  const std::string checkpoint = ReadTextFile(fs::path(R()) / "checkpoint.bin");
  const std::string renders = R() + "/renders/test";
  for (const char* name : {"checkpoint.bin", "config.json", "results.json", ".hdr4d-lock"}) {
    const std::string eval = "eval " + renders + " " + S() + "/images --out " + R() + "/" + name;
    ExpectRefused(RunHdr4d(eval), eval, "it is a file of training run");
  }
  const std::string view = "view " + R() + " --out " + R() + "/.hdr4d-lock";
  ExpectRefused(RunHdr4d(view), view, "it is a file of training run");
  EXPECT_EQ(ReadTextFile(fs::path(R()) / "checkpoint.bin"), checkpoint);
  EXPECT_EQ(RunHdr4d("eval " + renders + " " + S() + "/images --out " + R() + "/eval.json")
                .exit_code, 0);
  // The trainer itself still writes them: a resume to more iterations.
  EXPECT_EQ(RunHdr4d("train --out " + R() + " --resume --iterations 25 --threads 1").exit_code, 0);
}

// D2, D3: an edited config.json (learn_background flipped, resolved.hdr_colors flipped) made
// `train --resume` and `render` abort on an internal check, or render wrong images with exit 0.
// The checkpoint records the configuration it was trained with; a difference is refused by key.
TEST_F(RunReaders, D02AnEditedConfigurationIsRefusedByKeyAgainstTheCheckpoint) {
  TrainRun();
  const std::string background =
      EditedCopy("bg", [](json& c) { c["learn_background"] = !c["learn_background"].get<bool>(); });
  const std::string resume = "train --out " + background + " --resume --iterations 25 --threads 1";
  ExpectRefused(RunHdr4d(resume), resume, "learn_background");
  ExpectRefused(RunHdr4d(resume), resume, "checkpoint.bin was trained with");
  const std::string render = "render --run " + background + " --threads 1";
  ExpectRefused(RunHdr4d(render), render, "learn_background");
  const std::string colours = EditedCopy("colours", [](json& c) {
    c["resolved"]["hdr_colors"] = !c["resolved"]["hdr_colors"].get<bool>();
  });
  for (const std::string& command : {"render --run ", "export-ply --run ", "tone-curves --run "}) {
    const std::string args = command + colours;
    ExpectRefused(RunHdr4d(args), args, "resolved.hdr_colors");
  }
  const std::string dropped = EditedCopy("dropped", [](json& c) { c.erase("resolved"); });
  ExpectRefused(RunHdr4d("render --run " + dropped), "render", "has no resolved");
}

// D6: another run's checkpoint.bin was resumed and rendered under this run's configuration.
TEST_F(RunReaders, D06AnotherRunsCheckpointIsRefused) {
  TrainRun();
  const std::string other = (*this / "other").string();
  Train(other, "--seed 7 --supervision hdr");
  const fs::path mixed = *this / "mixed";
  fs::copy(R(), mixed, fs::copy_options::recursive);
  fs::copy_file(fs::path(other) / "checkpoint.bin", mixed / "checkpoint.bin",
                fs::copy_options::overwrite_existing);
  const std::string resume =
      "train --out " + mixed.string() + " --resume --iterations 25 --threads 1";
  ExpectRefused(RunHdr4d(resume), resume, "do not belong together");
  const std::string render = "render --run " + mixed.string();
  ExpectRefused(RunHdr4d(render), render, "do not belong together");
}

// D7, D8: a run rendered a changed scene (another field of view, a shortened split, another scene
// altogether) with exit 0; a moved scene said only "folder not found".
TEST_F(RunReaders, D07ARunIsShownOnlyOnTheCamerasItWasTrainedWith) {
  TrainRun();
  const fs::path test_json = fs::path(S()) / "transforms_test.json";
  const std::string original = ReadTextFile(test_json);
  json transforms = json::parse(original);
  transforms["camera_angle_x"] = transforms["camera_angle_x"].get<double>() * 2;
  testing::WriteTextFile(test_json, transforms.dump(2));
  const std::string render = "render --run " + R() + " --threads 1";
  ExpectRefused(RunHdr4d(render), render, "transforms_test.json changed");
  ExpectRefused(RunHdr4d("view " + R()), "view", "the scene changed since run");
  testing::WriteTextFile(test_json, original);
  // A changed image does not change what a render shows.
  testing::WriteTextFile(fs::path(S()) / "notes.txt", "x");
  EXPECT_EQ(RunHdr4d(render).exit_code, 0);
  fs::rename(S(), *this / "moved");
  const auto moved = RunHdr4d(render);
  ExpectRefused(moved, render, "config.json");
  ExpectRefused(moved, render, "'data'");
  ExpectRefused(moved, render, "is not there (moved or deleted");
}

// D8: export-ply, view and tone-curves called a HexPlane run's checkpoint "not an hdr4d
// checkpoint". (The run's config.json says what it is; a real HexPlane run trains for minutes.)
TEST_F(RunReaders, D08AHexPlaneRunIsNamedAsSuch) {
  TrainRun();
  const std::string grid = EditedCopy("grid", [](json& c) { c["hexplane"] = json::object(); });
  for (const std::string& command : {"export-ply --run ", "tone-curves --run ", "view "}) {
    const std::string args = command + grid;
    ExpectRefused(RunHdr4d(args), args, "a HexPlane run");
  }
}

// D9, D10: `render --timing` was ignored with --time and --video; `view` with both table sizes at
// their maxima ran for minutes towards a 4.6 GB page.
TEST_F(RunReaders, D09FlagsThatCannotApplyAndPagesTooLargeAreRefused) {
  TrainRun();
  for (const std::string& more : {"--time 0.5", "--video 2"}) {
    const std::string args = "render --run " + R() + " " + more + " --timing " + R() + "/t.json";
    ExpectRefused(RunHdr4d(args), args, "--timing times the views of a split render");
  }
  const auto start = std::chrono::steady_clock::now();
  const std::string view = "view " + R() + " --tone-nodes 65536 --exposure-steps 1024";
  ExpectRefused(RunHdr4d(view), view, "lower --tone-nodes or --exposure-steps");
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(60));
  EXPECT_FALSE(fs::exists(fs::path(R()) / "view.html"));
}

// D4: SIGTERM during `render --video` left every frame's temporary beyond the 256 tracked ones.
TEST_F(RunReaders, D04AStoppedVideoLeavesNoTemporaries) {
  TrainRun();
  const fs::path video = *this / "video";
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const std::string binary = testing::Hdr4dBinary();
    execl(binary.c_str(), "hdr4d", "render", "--run", R().c_str(), "--video", "20000", "--out",
          video.c_str(), "--threads", "1", static_cast<char*>(nullptr));
    _exit(127);
  }
  const auto temporaries = [&] {
    int n = 0;
    std::error_code ec;
    for (auto it = fs::directory_iterator(video, ec); !ec && it != fs::directory_iterator();
         it.increment(ec))
      n += it->path().filename().string()[0] == '.';
    return n;
  };
  // Up to two minutes: a loaded machine (ctest -j) is slow to start the frames.
  for (int i = 0; i < 12000 && temporaries() < 400; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_GE(temporaries(), 400);
  kill(child, SIGTERM);
  int status = 0;
  waitpid(child, &status, 0);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << status;
  EXPECT_EQ(temporaries(), 0);
}

// D12: a render that failed (a full disk) left the empty output folder it had made.
TEST_F(RunReaders, D12AFailedRenderTakesAwayTheFolderItMade) {
  TrainRun();
  const std::string small_disk = "bash -c 'trap \"\" XFSZ; ulimit -f 1; exec \"$0\" \"$@\"'";
  const fs::path out = *this / "new" / "renders";
  const auto r = testing::RunHdr4dWith(small_disk, "render --run " + R() + " --threads 1 --out " +
                                                       out.string());
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_FALSE(fs::exists(*this / "new"));
}

}  // namespace
}  // namespace hdr4d
