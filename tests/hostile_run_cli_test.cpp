// Issue 51, the second hostile sweep: the cases about run folders and what `train`, `render`,
// `synth-ldr` and `merge-hdr` do with files already there. Each test names the case of the
// issue it covers and failed before its fix.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "core/geometry/ply.h"
#include "core/image/image_io.h"
#include "tests/hostile_scene_fixture.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;
using testing::ReadTextFile;
using testing::RunHdr4d;
using testing::RunHdr4dWith;

// HostileScene (tests/hostile_scene_fixture.h) with a train that takes any scene and flags.
class RunSweep : public HostileScene {
 protected:
  std::string Train(const std::string& scene, const std::string& run, const std::string& more = "") {
    const auto r = RunHdr4d("train --data " + scene + " --out " + run +
                            " --iterations 20 --threads 1 " + more);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.err;
  }
};

json ReadJson(const fs::path& file) { return json::parse(ReadTextFile(file)); }

// Case 2: `render --timing R/results.json` and `export-ply --out R/results.json` replaced the
// run's results, exit 0. Every file of a run and its renders are inputs of what reads the run.
TEST_F(RunSweep, Case02ARunsFilesAndRendersAreInputsOfEveryCommandThatReadsIt) {
  Train(S(), R());
  ASSERT_EQ(RunHdr4d("render --run " + R()).exit_code, 0);
  const std::string results = ReadTextFile(fs::path(R()) / "results.json");
  const fs::path render = fs::path(R()) / "renders" / "test" / "cam03_t000_e0.png";
  const std::string render_bytes = ReadTextFile(render);
  for (const std::string& args :
       {"render --run " + R() + " --timing " + R() + "/results.json",
        "export-ply --run " + R() + " --out " + R() + "/results.json",
        "export-ply --run " + R() + " --out " + render.string(),
        "tone-curves --run " + R() + " --out " + R() + "/renders/test",
        "render --run " + R() + " --split train --timing " + render.string()}) {
    ExpectRefused(RunHdr4d(args), args, "refusing");
  }
  EXPECT_EQ(ReadTextFile(fs::path(R()) / "results.json"), results);
  EXPECT_EQ(ReadTextFile(render), render_bytes);
  // Its own renders a command may rewrite, and a new file beside the run's is fine.
  EXPECT_EQ(RunHdr4d("render --run " + R()).exit_code, 0);
  EXPECT_EQ(RunHdr4d("export-ply --run " + R() + " --out " + R() + "/model.ply").exit_code, 0);
}

// Case 3: `train --out RUN` without --resume silently replaced a finished run or a folder with an
// unrelated checkpoint.bin. Refused, naming --resume and --overwrite; --overwrite deletes what
// its help says and trains.
TEST_F(RunSweep, Case03ANewRunNeverReplacesAnEarlierOneUnlessAskedTo) {
  Train(S(), R());
  const std::string checkpoint = ReadTextFile(fs::path(R()) / "checkpoint.bin");
  const std::string args = "train --data " + S() + " --out " + R() + " --iterations 5 --threads 1";
  auto r = RunHdr4d(args);
  ExpectRefused(r, args, "finished run");
  ExpectRefused(r, args, "--resume");
  ExpectRefused(r, args, "--overwrite");
  EXPECT_EQ(ReadTextFile(fs::path(R()) / "checkpoint.bin"), checkpoint);
  const fs::path other = *this / "O";
  fs::create_directories(other);
  testing::WriteTextFile(other / "checkpoint.bin", "someone else's");
  const std::string args2 = "train --data " + S() + " --out " + other.string() + " --iterations 5 --threads 1";
  ExpectRefused(RunHdr4d(args2), args2, "checkpoint");
  EXPECT_EQ(ReadTextFile(other / "checkpoint.bin"), "someone else's");
  // --overwrite: its help names what it deletes; it trains anew and keeps other files.
  const auto help = RunHdr4d("train --help");
  EXPECT_NE(help.out.find("deletes its checkpoint.bin, config.json, results.json"), std::string::npos);
  testing::WriteTextFile(fs::path(R()) / "notes.txt", "mine");
  testing::WriteTextFile(fs::path(R()) / "best_val.bin", "an earlier run's best val model");
  r = RunHdr4d(args + " --overwrite");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadJson(fs::path(R()) / "results.json")["iterations"], 5);
  EXPECT_EQ(ReadTextFile(fs::path(R()) / "notes.txt"), "mine");
  EXPECT_FALSE(fs::exists(fs::path(R()) / "best_val.bin"));  // a run file: never another run's
}

// Rewrites a demo scene into the layout calibrate writes: images/camNN/tTTT_eE.png and
// hdr/camNN/tTTT.exr, so file names repeat across cameras.
void MoveIntoCameraFolders(const fs::path& scene) {
  for (const char* split : {"transforms_train.json", "transforms_test.json"}) {
    json j = ReadJson(scene / split);
    for (json& f : j["frames"]) {
      for (const char* key : {"file_path", "exr_file_path"}) {
        const fs::path old = f[key].get<std::string>();
        const std::string name = old.filename().string();  // cam03_t000_e0.png
        const fs::path moved = old.parent_path() / name.substr(0, 5) / name.substr(6);
        fs::create_directories(scene / moved.parent_path());
        if (fs::exists(scene / old)) fs::rename(scene / old, scene / moved);
        f[key] = moved.generic_string();
      }
    }
    testing::WriteTextFile(scene / split, j.dump(1));
  }
}

// Case 4: render flattened each frame's file_path to its name, so frames in sub-folders overwrote
// each other ("wrote 72 images", 16 files) and eval scored one camera against another's truth.
TEST_F(RunSweep, Case04RendersKeepTheFramesSubFoldersAndEvalPairsThem) {
  MoveIntoCameraFolders(S());
  ASSERT_TRUE(fs::exists(fs::path(S()) / "images" / "cam00" / "t000_e0.png"));
  Train(S(), R());
  const fs::path out = *this / "O";
  auto r = RunHdr4d("render --run " + R() + " --split train --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  int pngs = 0;
  for (const auto& e : fs::recursive_directory_iterator(out)) pngs += e.path().extension() == ".png";
  EXPECT_EQ(pngs, 36);  // 3 cameras x 4 times x 3 exposures
  EXPECT_TRUE(fs::exists(out / "cam00" / "t000_e0.png"));
  EXPECT_TRUE(fs::exists(out / "cam02" / "t003_e2.png"));
  r = RunHdr4d("eval " + out.string() + " " + S() + "/images --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  ASSERT_EQ(j["pairs"].size(), 36u);
  EXPECT_EQ(j["pairs"][0]["name"], "cam00/t000_e0.png");
  // Each render scored against its own camera's truth: a 20-step run is far from exact but
  // nothing like another view (the demo scene's cameras see different parts of the scene).
  const fs::path swapped = *this / "swapped";
  fs::copy(out, swapped, fs::copy_options::recursive);
  fs::rename(swapped / "cam00", swapped / "tmp");
  fs::rename(swapped / "cam01", swapped / "cam00");
  fs::rename(swapped / "tmp", swapped / "cam01");
  const json w = json::parse(RunHdr4d("eval " + swapped.string() + " " + S() + "/images --json").out);
  EXPECT_GT(j["mean"]["psnr"].get<double>(), w["mean"]["psnr"].get<double>());
}

// Case 6: synth-ldr --data replaced LDR images it did not make (no synthesis.json), silently.
TEST_F(RunSweep, Case06SynthLdrRefusesToReplaceImagesItDidNotMake) {
  fs::remove(fs::path(S()) / "synthesis.json");
  const fs::path photo = fs::path(S()) / "images" / "cam00_t000_e0.png";
  const std::string bytes = ReadTextFile(photo);
  const std::string args = "synth-ldr --data " + S() + " --crf gamma:2.2";
  auto r = RunHdr4d(args);
  ExpectRefused(r, args, "synthesis.json");
  ExpectRefused(r, args, "--overwrite");
  EXPECT_EQ(ReadTextFile(photo), bytes);
  EXPECT_FALSE(fs::exists(fs::path(S()) / "synthesis.json"));
  r = RunHdr4d(args + " --overwrite");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(ReadTextFile(photo), bytes);
  // Its own images (synthesis.json there) it replaces as before.
  EXPECT_EQ(RunHdr4d("synth-ldr --data " + S()).exit_code, 0);
}

// Case 12: a huge point3d.ply on a tiny scene grew train until it was OOM-killed, leaving
// config.json and the lock; --max-gaussians did not cap the initial cloud. The memory is checked
// from the PLY's header first (here under a 3 GB address-space limit), and the budget
// subsamples the cloud.
TEST_F(RunSweep, Case12AHugePointCloudIsCheckedUpFrontAndCappedByTheBudget) {
  PointCloud cloud;
  const int n = 3'000'000;
  cloud.positions.resize(n);
  for (int i = 0; i < n; ++i)
    cloud.positions[i] = Eigen::Vector3f(0.3f * std::sin(i * 0.1f), 0.3f * std::cos(i * 0.37f),
                                         0.3f * std::sin(i * 0.77f));
  WritePly(fs::path(S()) / "point3d.ply", cloud);
  const std::string limit = "bash -c 'ulimit -v 3000000; exec \"$0\" \"$@\"'";
  const std::string args = "train --data " + S() + " --out " + R() + " --iterations 5 --threads 1";
  auto r = RunHdr4dWith(limit, args);
  ExpectRefused(r, args, "--max-gaussians");
  ExpectRefused(r, args, "GiB");
  EXPECT_FALSE(fs::exists(R())) << "a refused start left its run folder";
  r = RunHdr4dWith(limit, args + " --max-gaussians 2000");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_LE(ReadJson(fs::path(R()) / "results.json")["gaussians"].get<int>(), 2000);
}

// Case 15: --resume did not notice a changed dataset (an image swapped for another of the same
// size, the frame order reversed). The run records its data's checksums and compares.
TEST_F(RunSweep, Case15ResumeRefusesAChangedDatasetNamingTheChange) {
  Train(S(), R());
  const std::string resume = "train --out " + R() + " --resume --iterations 30 --threads 1";
  const fs::path images = fs::path(S()) / "images";
  fs::copy_file(images / "cam00_t000_e0.png", *this / "keep.png");
  fs::copy_file(images / "cam01_t000_e0.png", images / "cam00_t000_e0.png",
                fs::copy_options::overwrite_existing);
  ExpectRefused(RunHdr4d(resume), resume, "images/cam00_t000_e0.png changed");
  fs::copy_file(*this / "keep.png", images / "cam00_t000_e0.png", fs::copy_options::overwrite_existing);
  const fs::path train_json = fs::path(S()) / "transforms_train.json";
  const std::string original = ReadTextFile(train_json);
  json j = json::parse(original);
  std::reverse(j["frames"].begin(), j["frames"].end());
  testing::WriteTextFile(train_json, j.dump(1));
  ExpectRefused(RunHdr4d(resume), resume, "frame 0 was");
  testing::WriteTextFile(train_json, original);
  const auto r = RunHdr4d(resume);
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// Case 18: --resume of a finished run rewrote results.json and the checkpoint; merge-hdr of
// brackets clipped everywhere wrote a constant HDR without a word.
TEST_F(RunSweep, Case18ResumingAFinishedRunRewritesNothing) {
  Train(S(), R());
  const auto time_of = [&](const char* name) { return fs::last_write_time(fs::path(R()) / name); };
  const auto results = time_of("results.json"), checkpoint = time_of("checkpoint.bin"),
             config = time_of("config.json");
  const std::string text = ReadTextFile(fs::path(R()) / "results.json");
  ::usleep(20'000);
  const auto r = RunHdr4d("train --out " + R() + " --resume --threads 1");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("is finished"), std::string::npos) << r.err;
  EXPECT_EQ(time_of("results.json"), results);
  EXPECT_EQ(time_of("checkpoint.bin"), checkpoint);
  EXPECT_EQ(time_of("config.json"), config);
  EXPECT_EQ(ReadTextFile(fs::path(R()) / "results.json"), text);
}

TEST_F(RunSweep, Case18MergeHdrOfBracketsClippedEverywhereWarns) {
  for (const auto& e : fs::directory_iterator(fs::path(S()) / "images")) {
    const Image ldr = ReadImage(e.path());
    Image white(ldr.width(), ldr.height(), ldr.channels(), ldr.encoding(), 1.0f);
    WriteImage(e.path(), white);
  }
  const auto r = RunHdr4d("merge-hdr --data " + S() + " --out " + (*this / "M").string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("clipped"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("constant"), std::string::npos) << r.err;
}

// Case 20: a full disk during train left config.json and the lock, and a resume said
// "checkpoint not found". Simulated with a file-size limit (SIGXFSZ ignored: writes fail with
// EFBIG as on a full disk): the failed start leaves no run folder; a folder left with a config
// and no checkpoint is named as such on resume.
TEST_F(RunSweep, Case20AFullDiskDuringTrainLeavesNoHalfRun) {
  const std::string small_disk = "bash -c 'trap \"\" XFSZ; ulimit -f 64; exec \"$0\" \"$@\"'";
  const std::string args = "train --data " + S() + " --out " + R() + " --iterations 5 --threads 1";
  const auto r = RunHdr4dWith(small_disk, args);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_FALSE(fs::exists(R())) << "left: " << (fs::exists(R() + "/config.json") ? "config.json" : "");
  // A folder a killed start left (config, no checkpoint).
  Train(S(), R());
  fs::remove(fs::path(R()) / "checkpoint.bin");
  fs::remove(fs::path(R()) / "results.json");
  const std::string resume = "train --out " + R() + " --resume --threads 1";
  const auto resumed = RunHdr4d(resume);
  ExpectRefused(resumed, resume, "no checkpoint.bin");
  ExpectRefused(resumed, resume, "--overwrite");
}

// Case 24: appended bytes were reported as a truncated checkpoint; `render --video --out V%02d`
// failed in ffmpeg; synth-ldr on a read-only scene named a temporary file, not the cause.
TEST_F(RunSweep, Case24AppendedBytesVideoPatternsAndReadOnlyScenesAreNamed) {
  Train(S(), R());
  {
    std::ofstream append(fs::path(R()) / "checkpoint.bin", std::ios::app | std::ios::binary);
    append << "trailing garbage";
  }
  const std::string render = "render --run " + R() + " --out " + (*this / "O").string();
  auto r = RunHdr4d(render);
  ExpectRefused(r, render, "16 bytes were appended");
  EXPECT_EQ(r.err.find("truncated"), std::string::npos) << r.err;

  Train(S(), R(), "--overwrite");
  if (std::system("command -v ffmpeg >/dev/null 2>&1") == 0) {
    const fs::path video = *this / "V%02d";
    r = RunHdr4d("render --run " + R() + " --video 3 --out '" + video.string() + "'");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(fs::exists(video / "video.mp4")) << r.err;
  }

  if (std::system("command -v setpriv >/dev/null 2>&1") != 0) GTEST_SKIP() << "no setpriv";
  const std::string nobody = "setpriv --reuid=65534 --regid=65534 --clear-groups";
  if (RunHdr4dWith(nobody, "--version").exit_code != 0)
    GTEST_SKIP() << "the hdr4d binary cannot be run as uid 65534 here";
  fs::permissions(dir_.path(), fs::perms(0755));
  const std::string synth = "synth-ldr --data " + S();
  r = RunHdr4dWith(nobody, synth);
  ExpectRefused(r, synth, "read-only");
  EXPECT_EQ(r.err.find(".tmp"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace hdr4d
