// The hdr4d binary used as a hostile or careless user would (issue 11): nothing already written
// is lost, nothing silently wrong, no crash, and every mistake is one line naming the file and
// the problem with exit code 1. Each test names the case of the issue it covers.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <limits>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>

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

int LineCount(const std::string& s) {
  return static_cast<int>(std::count(s.begin(), s.end(), '\n'));
}

// Exit code 1 and exactly one line on stderr, hdr4d's, containing every one of `parts`.
void ExpectOneLineError(const testing::CommandResult& r,
                        const std::string& args,
                        const std::vector<std::string>& parts) {
  EXPECT_EQ(r.exit_code, 1) << args << "\n" << r.err;
  EXPECT_EQ(LineCount(r.err), 1) << args << "\n" << r.err;
  EXPECT_EQ(r.err.rfind("hdr4d: error: ", 0), 0u) << args << "\n" << r.err;
  for (const std::string& part : parts)
    EXPECT_NE(r.err.find(part), std::string::npos) << args << "\nmissing: " << part << "\n" << r.err;
}

// For a problem found while working: progress lines may come first, then hdr4d's one error line,
// last.
void ExpectErrorLast(const testing::CommandResult& r,
                     const std::string& args,
                     const std::vector<std::string>& parts) {
  EXPECT_EQ(r.exit_code, 1) << args << "\n" << r.err;
  std::string last = r.err.substr(0, r.err.empty() ? 0 : r.err.size() - 1);
  last = last.substr(last.rfind('\n') == std::string::npos ? 0 : last.rfind('\n') + 1);
  EXPECT_EQ(last.rfind("hdr4d: error: ", 0), 0u) << args << "\n" << r.err;
  int error_lines = 0;
  std::istringstream lines(r.err);
  for (std::string line; std::getline(lines, line);) error_lines += line.find("error") != std::string::npos;
  EXPECT_EQ(error_lines, 1) << args << "\n" << r.err;
  for (const std::string& part : parts)
    EXPECT_NE(last.find(part), std::string::npos) << args << "\nmissing: " << part << "\n" << r.err;
}

// Every file under `root` with its bytes (symlinks as their target's text).
std::map<std::string, std::string> Snapshot(const fs::path& root) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    const std::string rel = fs::relative(e.path(), root).string();
    if (e.is_symlink()) {
      files[rel] = "-> " + fs::read_symlink(e.path()).string();
    } else if (e.is_regular_file()) {
      files[rel] = ReadTextFile(e.path());
    } else if (e.is_directory()) {
      files[rel + "/"] = "";
    }
  }
  return files;
}

using Hostile = HostileScene;  // tests/hostile_scene_fixture.h: S, R, TrainRun()

// --- Data loss ---------------------------------------------------------------------------------

// Case 1: render and merge-hdr into a dataset's image folders overwrote the ground truth.
TEST_F(Hostile, Case01NoCommandWritesIntoADatasetsImageFolders) {
  TrainRun();
  fs::create_symlink(fs::path(S()) / "images", *this / "alias");
  const auto before = Snapshot(S());
  for (const std::string& args :
       {"render --run " + R() + " --out " + S() + "/images", "render --run " + R() + " --out " + S() + "/hdr",
        "render --run " + R() + " --out " + (*this / "alias").string(),
        "render --run " + R() + " --time 0.5 --out " + S() + "/images",
        "render --run " + R() + " --video 2 --out " + S() + "/hdr",
        "merge-hdr --data " + S() + " --out " + S() + "/hdr",
        "merge-hdr --data " + S() + " --out " + S() + "/images",
        "tone-curves --run " + R() + " --out " + S() + "/images",
        "dataset preview " + S() + " --out " + S() + "/images/preview.png",
        "export-ply --run " + R() + " --out " + S() + "/point3d.ply",
        "train --data " + S() + " --out " + S() + "/images --iterations 2"}) {
    ExpectOneLineError(RunHdr4d(args), args, {"refusing to write"});
  }
  EXPECT_EQ(Snapshot(S()), before);
}

// Case 2: synth-ldr IN --out IN destroyed its input, eval --out G replaced the ground truth.
TEST_F(Hostile, Case02NoCommandWritesOverItsOwnInput) {
  TrainRun();
  const std::string exr = S() + "/hdr/cam00_t000.exr";
  fs::create_symlink(exr, *this / "link.exr");
  fs::create_hard_link(exr, *this / "hard.exr");
  fs::copy_file(exr, *this / "p.exr");
  const auto before = Snapshot(dir_.path());
  for (const std::string& args :
       {"synth-ldr " + exr + " --out " + exr, "synth-ldr " + exr + " --out " + S() + "/hdr/../hdr/cam00_t000.exr",
        "synth-ldr " + exr + " --out " + (*this / "link.exr").string(),
        "synth-ldr " + exr + " --out " + (*this / "hard.exr").string(),
        "eval " + (*this / "p.exr").string() + " " + exr + " --out " + exr,
        "eval " + (*this / "p.exr").string() + " " + exr + " --out " + (*this / "p.exr").string(),
        "eval " + S() + "/hdr " + S() + "/hdr --out " + S() + "/hdr/scores.json",
        "export-ply --run " + R() + " --out " + R() + "/checkpoint.bin",
        "export-ply --run " + R() + " --out " + R() + "/config.json"}) {
    ExpectOneLineError(RunHdr4d(args), args, {"refusing to write"});
  }
  EXPECT_EQ(Snapshot(dir_.path()), before);
}

// Case 3: as root, `eval ... --out /dev/null` replaced the device node with a regular file. A
// private node and a FIFO stand in for /dev/null, so a regression cannot break the machine.
TEST_F(Hostile, Case03SpecialFilesAndSymlinksAreWrittenThrough) {
  const std::string hdr = S() + "/hdr";
  fs::create_directories(*this / "real");
  fs::create_symlink(*this / "real" / "scores.json", *this / "link.json");
  auto r = RunHdr4d("eval " + hdr + " " + hdr + " --out " + (*this / "link.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(*this / "link.json"));
  EXPECT_TRUE(json::parse(ReadTextFile(*this / "real" / "scores.json")).contains("mean"));

  const fs::path fifo = *this / "fifo.json";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] { received = ReadTextFile(fifo); });
  r = RunHdr4d("eval " + hdr + " " + hdr + " --out " + fifo.string());
  reader.join();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_fifo(fifo));
  EXPECT_TRUE(json::parse(received).contains("pairs"));

  const fs::path node = *this / "null";
  if (::mknod(node.c_str(), S_IFCHR | 0666, makedev(1, 3)) != 0)
    GTEST_SKIP() << "mknod needs root (the symlink and FIFO cases ran)";
  r = RunHdr4d("eval " + hdr + " " + hdr + " --out " + node.string());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_character_file(node));
}

// Case 4: make-demo-scene over an existing dataset overwrote part of it and left stale files.
TEST_F(Hostile, Case04SceneMakersNeverMergeIntoAnExistingFolder) {
  const auto before = Snapshot(S());
  for (const std::string& args :
       {"make-demo-scene --out " + S() + " --size 16 --timestamps 2 --cameras 2",
        "make-gaussian-scene --out " + S() + " --size 16 --cameras 4 --timestamps 2"}) {
    ExpectOneLineError(RunHdr4d(args), args, {S() + ": exists and is not empty"});
  }
  EXPECT_EQ(Snapshot(S()), before);
  // An empty folder is fine, and no work folder is left beside it.
  fs::create_directories(*this / "empty");
  const auto r = RunHdr4d("make-demo-scene --out " + (*this / "empty").string() +
                          " --size 16 --timestamps 2 --cameras 2 --spp 1");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(*this / "empty" / "transforms_train.json"));
  for (const auto& e : fs::directory_iterator(dir_.path()))
    EXPECT_EQ(e.path().filename().string().find("staging"), std::string::npos) << e.path();
}

// --- Crashes -----------------------------------------------------------------------------------

// Case 5: a value nested 60000 deep segfaulted dataset check, train and synth-ldr.
TEST_F(Hostile, Case05DeeplyNestedJsonIsAProblemNotACrash) {
  const fs::path train_json = fs::path(S()) / "transforms_train.json";
  json doc = json::parse(ReadTextFile(train_json));
  const std::string deep = std::string(60000, '[') + "0.5" + std::string(60000, ']');
  std::string text = doc.dump();
  const std::string key = "\"time\":";
  text.replace(text.find(key) + key.size(), 3, deep);  // the first frame's time is 0.0
  testing::WriteTextFile(train_json, text);
  const auto check = RunHdr4d("dataset check " + S());
  EXPECT_EQ(check.exit_code, 1) << check.err;
  EXPECT_NE(check.out.find("transforms_train.json: invalid JSON: nested deeper than 256 levels"),
            std::string::npos)
      << check.out;
  for (const std::string& args : {"train --data " + S() + " --out " + R(), "synth-ldr --data " + S()})
    ExpectOneLineError(RunHdr4d(args), args, {"transforms_train.json", "nested deeper"});
  testing::WriteTextFile(train_json, std::string(100000, '[') + std::string(100000, ']'));
  EXPECT_EQ(RunHdr4d("dataset check " + S()).exit_code, 1);
}

// --- Silent wrong results ----------------------------------------------------------------------

// FNV-1a over `bytes`, as the checkpoint trailer stores it (core/files/binary_stream.h), written out
// independently here so a test can write a damaged checkpoint that still passes the checksum and
// reach the value checks.
std::uint64_t Fnv1a(const std::string& bytes) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  return h;
}

// Case 6: damage in the Gaussian section, NaN values and header edits were resumed silently.
TEST_F(Hostile, Case06DamagedCheckpointsAreRefusedOnResumeAndRender) {
  TrainRun();
  const fs::path ckpt = fs::path(R()) / "checkpoint.bin";
  const std::string good = ReadTextFile(ckpt);
  std::uint64_t header_size = 0;
  std::memcpy(&header_size, good.data() + 8, 8);
  const std::size_t first_value = 16 + header_size + 8;  // xyz[0], after its count
  const std::string resume =
      "train --data " + S() + " --out " + R() + " --iterations 30 --threads 1 --resume";
  const std::string render = "render --run " + R() + " --out " + (*this / "renders").string();

  // One flipped byte in the Gaussian section, and a hand edit of the header's iteration.
  std::string flipped = good;
  flipped[first_value + 5] ^= 0x10;
  std::string edited = good;
  const std::size_t at = edited.find("\"iteration\":20");
  ASSERT_NE(at, std::string::npos);
  edited[at + 13] = '1';
  for (const std::string* bytes : {&flipped, &edited}) {
    testing::WriteTextFile(ckpt, *bytes);
    ExpectErrorLast(RunHdr4d(resume), resume, {ckpt.string(), "checksum"});
    ExpectErrorLast(RunHdr4d(render), render, {ckpt.string(), "checksum"});
    EXPECT_EQ(ReadTextFile(ckpt), *bytes);  // refused, not rewritten
  }

  // A NaN position with a checksum that matches (a writer's mistake): the values are checked.
  std::string nan = good.substr(0, good.size() - 8);
  const float value = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(nan.data() + first_value, &value, 4);
  const std::uint64_t sum = Fnv1a(nan.substr(0, nan.size() - 8));
  nan.append(reinterpret_cast<const char*>(&sum), 8);
  testing::WriteTextFile(ckpt, nan);
  ExpectErrorLast(RunHdr4d(resume), resume, {ckpt.string(), "xyz", "nan"});
  ExpectErrorLast(RunHdr4d(render), render, {ckpt.string(), "xyz", "nan"});
  EXPECT_FALSE(fs::exists(*this / "renders"));
}

// Case 7: two trainings into one run folder at once both succeeded and mixed their files.
TEST_F(Hostile, Case07ASecondTrainingIntoABusyRunFolderIsRefused) {
  const std::string first = "train --data " + S() + " --out " + R() +
                            " --iterations 1000000 --max-seconds 6 --threads 1";
  testing::CommandResult first_result;
  std::thread holder([&] { first_result = RunHdr4d(first); });
  const fs::path lock = fs::path(R()) / ".hdr4d-lock";
  for (int i = 0; i < 400 && ReadTextFile(lock).empty(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  const std::string second =
      "train --data " + S() + " --out " + R() + " --iterations 20 --threads 1 --seed 9";
  ExpectOneLineError(RunHdr4d(second), second, {R(), "in use by hdr4d train", "pid"});
  holder.join();
  EXPECT_EQ(first_result.exit_code, 0) << first_result.err;
  // The folder is the first run's alone.
  const json config = json::parse(ReadTextFile(fs::path(R()) / "config.json"));
  EXPECT_EQ(config.at("seed"), 0);
  EXPECT_EQ(config.at("optimization").at("iterations"), 1000000);
  // Released when the first ended: a resume may take it.
  EXPECT_EQ(RunHdr4d("train --data " + S() + " --out " + R() +
                     " --iterations 1000000 --max-seconds 1 --threads 1 --resume")
                .exit_code,
            0);
}

// Case 8: --resume with another scene, seed or HDR weight rewrote config.json, crashed or
// trained with values that config.json then misreported.
TEST_F(Hostile, Case08ResumeRefusesAnotherConfigurationBeforeWritingAnything) {
  TrainRun();
  fs::copy(S(), *this / "OTHER", fs::copy_options::recursive);
  const auto before = Snapshot(R());
  const std::string base = " --out " + R() + " --iterations 40 --resume";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"train --data " + (*this / "OTHER").string() + base, "data"},
      {"train --data " + S() + base + " --seed 3", "seed = 3"},
      {"train --data " + S() + base + " --hdr-weight 0.5", "hdr.hdr_weight = 0.5"},
      {"train --data " + S() + base + " --densify-grad-threshold 0.01",
       "optimization.densify_grad_threshold = 0.01"},
      {"train --data " + S() + base + " --tone-mapper sigmoid", "tone_mapper"},
  };
  for (const auto& [args, key] : cases) {
    ExpectOneLineError(RunHdr4d(args), args,
                       {(fs::path(R()) / "config.json").string(), key, "a resumed run keeps"});
    EXPECT_EQ(Snapshot(R()), before) << args;  // nothing written
  }
  // What may differ: the run length and threads. It continues, and says what it used.
  const auto r = RunHdr4d("train --data " + S() + base + " --threads 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json config = json::parse(ReadTextFile(fs::path(R()) / "config.json"));
  EXPECT_EQ(config.at("threads"), 2);
  EXPECT_EQ(config.at("optimization").at("iterations"), 40);
  // The schedules that follow the run length stay those the run started with (20 iterations).
  const json started = json::parse(before.at("config.json"));
  EXPECT_EQ(config.at("optimization").at("densify_until"),
            started.at("optimization").at("densify_until"));
  // Without a saved configuration there is nothing to resume.
  fs::remove(fs::path(R()) / "config.json");
  const std::string lost = "train --data " + S() + base;
  ExpectOneLineError(RunHdr4d(lost), lost, {"config.json", "no run here to resume"});
}

// Case 8b: a long run is resumed with the run folder alone: its own scene and options (not the
// defaults), and another option is refused before the scene is read.
TEST_F(Hostile, Case08bResumeNeedsOnlyTheRunFolderAndChecksBeforeReadingTheScene) {
  auto r = RunHdr4d("train --data " + S() + " --out " + R() +
                    " --iterations 20 --threads 1 --seed 3 --supervision ldr --hdr-weight 0.5 "
                    "--densify-grad-threshold 0.01 --no-learn-background");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json started = json::parse(ReadTextFile(fs::path(R()) / "config.json"));
  r = RunHdr4d("train --out " + R() + " --resume --iterations 30 --threads 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  json resumed = json::parse(ReadTextFile(fs::path(R()) / "config.json"));
  EXPECT_EQ(resumed.at("optimization").at("iterations"), 30);
  resumed["optimization"]["iterations"] = started.at("optimization").at("iterations");
  EXPECT_EQ(resumed, started);  // seed, supervision, weights, schedules, background: the run's own
  // With the scene's images gone, a different option is still named first: nothing was read.
  fs::remove_all(fs::path(S()) / "images");
  const auto before = Snapshot(R());
  for (const std::string& flag : {std::string(" --seed 4"), std::string(" --learn-background"),
                                  std::string(" --method 4dgs")}) {
    const std::string args = "train --out " + R() + " --resume --iterations 40" + flag;
    ExpectOneLineError(RunHdr4d(args), args,
                       {(fs::path(R()) / "config.json").string(), "a resumed run keeps"});
    EXPECT_EQ(Snapshot(R()), before) << args;
  }
  // A damaged record is named with the key at fault.
  json bad = started;
  bad["optimization"].erase("densify_until");
  std::ofstream(fs::path(R()) / "config.json") << bad.dump();
  const std::string args = "train --out " + R() + " --resume";
  ExpectOneLineError(RunHdr4d(args), args, {"config.json", "key 'optimization.densify_until' is missing"});
}

// Case 9: flags silently replaced by defaults, wrapped or ignored.
TEST_F(Hostile, Case09EveryFlagIsValidatedBeforeAnythingRuns) {
  TrainRun();
  const std::string train = "train --data " + S() + " --out " + (*this / "X").string();
  const std::string render = "render --run " + R() + " --out " + (*this / "Y").string();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {train + " --context-window 0", "--context-window"},
      {train + " --context-window -4", "--context-window"},
      {train + " --context-size 0", "--context-size"},
      {train + " --context-size -1", "--context-size"},
      {train + " --seed -1", "--seed"},
      {train + " --seed 18446744073709551616", "--seed"},
      {train + " --random-points 0", "--random-points"},
      {train + " --threads -2", "--threads"},
      {train + " --background nan", "--background"},
      {train + " --hdr-weight inf", "--hdr-weight"},
      {render + " --video 0", "--video"},
      {render + " --video -3", "--video"},
      {render + " --threads -2", "--threads"},
      {render + " --video 3 --fps 0", "--fps"},
      {render + " --time 0.5 --video 3", "--video"},
      {render + " --exposure -1", "--exposure"},
      {"export-ply --run " + R() + " --time 1.5", "--time"},
      {"synth-ldr --data " + S() + " --bits 12", "--bits"},
      {"make-demo-scene --out " + (*this / "Z").string() + " --size 0", "--size"},
      {"dataset preview " + S() + " --out " + (*this / "p.png").string() + " --columns 0",
       "--columns"},
  };
  for (const auto& [args, flag] : cases) ExpectOneLineError(RunHdr4d(args), args, {flag});
  for (const char* name : {"X", "Y", "Z", "p.png"}) EXPECT_FALSE(fs::exists(*this / name)) << name;
  // A given --context-window 20 is the value 20, not "unset".
  const auto r = RunHdr4d(train + " --iterations 2 --context-window 20 --context-size 2");
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// Case 10: what training refuses, `dataset check --full` finds, and synth-ldr names the file.
TEST_F(Hostile, Case10DatasetCheckFindsWhatTrainingRefuses) {
  const fs::path exr = fs::path(S()) / "hdr" / "cam01_t002.exr";
  Image hdr = ReadImage(exr);
  hdr.at(3, 4, 1) = -2.0f;
  WriteImage(exr, hdr, {.format = PixelFormat::kFloat});
  auto r = RunHdr4d("dataset check " + S() + " --full");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("cam01_t002.exr: negative radiance -2 at x=3, y=4"), std::string::npos)
      << r.out;
  const auto ldr_before = Snapshot(fs::path(S()) / "images");
  ExpectErrorLast(RunHdr4d("train --data " + S() + " --out " + R() + " --iterations 2"), "train",
                  {"cam01_t002.exr", "negative radiance"});
  ExpectErrorLast(RunHdr4d("synth-ldr --data " + S() + " --seed 7"), "synth-ldr --data",
                  {"cam01_t002.exr", "negative radiance"});
  // All or nothing: the LDR images made before the bad one was found are not in place.
  EXPECT_EQ(Snapshot(fs::path(S()) / "images"), ldr_before);
  ExpectOneLineError(RunHdr4d("synth-ldr " + exr.string() + " --out " + (*this / "o.png").string()),
                     "synth-ldr", {exr.string(), "not a radiance"});

  // A file_path naming an EXR (with a NaN): found by the full check, refused by train.
  Image nan_image = ReadImage(fs::path(S()) / "hdr" / "cam00_t000.exr");
  nan_image.at(0, 0, 0) = std::numeric_limits<float>::quiet_NaN();
  WriteImage(*this / "nan.exr", nan_image, {.format = PixelFormat::kFloat});
  json test = json::parse(ReadTextFile(fs::path(S()) / "transforms_test.json"));
  test["frames"][0]["file_path"] = (*this / "nan.exr").string();
  testing::WriteTextFile(fs::path(S()) / "transforms_test.json", test.dump());
  r = RunHdr4d("dataset check " + S() + " --full");
  EXPECT_NE(r.out.find("nan.exr: non-finite pixel value (nan)"), std::string::npos) << r.out;
}

TEST_F(Hostile, Case10SynthLdrRefusesAnExrOfAnotherSizeThanTheJson) {
  WriteImage(fs::path(S()) / "hdr" / "cam02_t001.exr", Image(40, 32, 3, Encoding::kLinear, 1.0f),
             {.format = PixelFormat::kFloat});
  ExpectOneLineError(RunHdr4d("synth-ldr --data " + S()), "synth-ldr",
                     {"cam02_t001.exr: HDR image is 40x32", "is 32x32"});
}

// Case 11: one identical pair made every PSNR mean null / inf.
TEST_F(Hostile, Case11EvalMeansAreOverFiniteValuesAndCountIdenticalPairs) {
  const fs::path pred = *this / "pred";
  fs::create_directories(pred);
  for (const auto& e : fs::directory_iterator(fs::path(S()) / "hdr")) {
    Image image = ReadImage(e.path());
    if (e.path().filename() != "cam00_t000.exr") image.at(1, 1, 0) += 0.25f;
    WriteImage(pred / e.path().filename(), image, {.format = PixelFormat::kFloat});
  }
  auto r = RunHdr4d("eval " + pred.string() + " " + S() + "/hdr --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json result = json::parse(r.out);
  EXPECT_EQ(result["identical_pairs"], 1);
  for (const char* key : {"mu_psnr", "pu21_psnr", "mu_psnr_gt_max"})
    EXPECT_TRUE(result["mean"][key].is_number()) << key << ": " << result["mean"];
  r = RunHdr4d("eval " + pred.string() + " " + S() + "/hdr");
  EXPECT_NE(r.out.find("identical: 1 of 16 pairs"), std::string::npos) << r.out;
  const std::string mean_line = r.out.substr(r.out.find("\nmean"));
  EXPECT_EQ(mean_line.substr(0, mean_line.find("\nidentical")).find("inf"), std::string::npos)
      << r.out;
}

// --- Leftovers ---------------------------------------------------------------------------------

// Case 12: kill -9 of render --video left frame_0192.png.tmpPID.png, which later evals rejected.
// Whatever the moment of the kill, every file an image reader sees is a complete image.
TEST_F(Hostile, Case12AKilledRenderLeavesNoHalfImageBehind) {
  TrainRun();
  const std::string video = (*this / "video").string();
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const std::string binary = testing::Hdr4dBinary();
    execl(binary.c_str(), "hdr4d", "render", "--run", R().c_str(), "--video", "400", "--out",
          video.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait for the first frames, then kill -9 mid-stream.
  // Up to a minute: a loaded machine (ctest -j) can be slow to start the first frames.
  for (int i = 0; i < 6000 && !fs::exists(fs::path(video) / "frame_0003.png"); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  kill(child, SIGKILL);
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(fs::exists(video));
  for (const auto& e : fs::directory_iterator(video)) {
    const std::string name = e.path().filename().string();
    // A killed write's temporary file is hidden and has no image extension.
    if (name[0] == '.') {
      EXPECT_EQ(name.find(".png", name.size() - 4), std::string::npos) << name;
      continue;
    }
    if (e.path().extension() == ".png") {
      EXPECT_NO_THROW(ReadImage(e.path())) << name;
    }
  }
  const auto r = RunHdr4d("eval " + video + " " + video + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

TEST_F(Hostile, Case12AFailedCommandLeavesNoEmptyOutputFolder) {
  for (const std::string& args :
       {"train --data " + S() + " --out " + (*this / "run0").string() + " --random-points 0",
        "make-demo-scene --out " + (*this / "scene0").string() + " --exposures 1,-2",
        "render --run " + (*this / "nope").string() + " --out " + (*this / "renders0").string()}) {
    ExpectOneLineError(RunHdr4d(args), args, {});
  }
  for (const char* name : {"run0", "scene0", "renders0"}) EXPECT_FALSE(fs::exists(*this / name));
}

// --- Messages ----------------------------------------------------------------------------------

// Case 13: for a truncated PNG, libpng's "PNG library error" came after hdr4d's line.
TEST_F(Hostile, Case13ATruncatedPngIsOneLineFromHdr4d) {
  const std::string png = ReadTextFile(fs::path(S()) / "images" / "cam00_t000_e0.png");
  testing::WriteTextFile(*this / "cut.png", png.substr(0, 300));
  const std::string args =
      "eval " + (*this / "cut.png").string() + " " + S() + "/images/cam00_t000_e0.png";
  ExpectOneLineError(RunHdr4d(args), args, {"cut.png: cannot read image: truncated PNG"});
}

// Case 14: parse errors exited 104/106/109 with two lines.
TEST_F(Hostile, Case14CommandLineMistakesExitOneWithOneLine) {
  for (const auto& [args, text] : std::vector<std::pair<std::string, std::string>>{
           {"train --data " + S() + " --out " + R() + " --iterations abc", "--iterations"},
           {"train --data " + S() + " --out " + R() + " --iterationz 3", "--iterationz"},
           {"tone-curves --run " + R() + " --times a,b", "--times"},
           {"train --data " + S(), "--out"},
           {"trian --data " + S(), "trian"},
           {"dataset", "check, preview or split-val"},
           {"", "subcommand"}}) {
    ExpectOneLineError(RunHdr4d(args), args, {text});
  }
  EXPECT_EQ(RunHdr4d("train --help").exit_code, 0);
  EXPECT_EQ(RunHdr4d("--version").exit_code, 0);
}

// Case 15: a folder without read permission was reported as "file not found".
TEST_F(Hostile, Case15UnreadableInputsSayPermissionDenied) {
  if (std::system("command -v setpriv >/dev/null 2>&1") != 0) GTEST_SKIP() << "no setpriv";
  const std::string nobody = "setpriv --reuid=65534 --regid=65534 --clear-groups";
  if (RunHdr4dWith(nobody, "--version").exit_code != 0)
    GTEST_SKIP() << "the hdr4d binary cannot be run as uid 65534 here";
  fs::permissions(dir_.path(), fs::perms(0755));
  fs::permissions(S(), fs::perms(0700));  // nobody may not enter it
  auto r = RunHdr4dWith(nobody, "dataset check " + S());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find(S() + ": permission denied"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("not found"), std::string::npos) << r.out;
  const std::string png = S() + "/images/cam00_t000_e0.png";
  ExpectOneLineError(RunHdr4dWith(nobody, "eval " + png + " " + png), "eval",
                     {png + ": permission denied"});
  fs::permissions(S(), fs::perms(0755));
  fs::permissions(fs::path(S()) / "transforms_train.json", fs::perms(0600));
  r = RunHdr4dWith(nobody, "dataset check " + S());
  EXPECT_NE(r.out.find("transforms_train.json: permission denied"), std::string::npos) << r.out;
}

// Case 16: a wrong type in a run's config.json was nlohmann's type_error naming no file or key.
TEST_F(Hostile, Case16WrongJsonTypesNameTheFileAndTheKey) {
  TrainRun();
  const fs::path config = fs::path(R()) / "config.json";
  json doc = json::parse(ReadTextFile(config));
  doc["background"] = "grey";
  testing::WriteTextFile(config, doc.dump());
  for (const std::string& args : {"render --run " + R(), "export-ply --run " + R()}) {
    ExpectOneLineError(RunHdr4d(args), args,
                       {"config.json: key 'background': expected a number, got string \"grey\""});
  }
  doc["background"] = 0;
  doc["resolved"]["hdr"] = "yes";
  testing::WriteTextFile(config, doc.dump());
  ExpectOneLineError(RunHdr4d("render --run " + R()), "render", {"key 'resolved.hdr'"});
}

// Issue 51 §24: flag mistakes named the wrong thing. A repeated flag said "At Most 1 required but
// received 2", `--config /dev/null` "no such file and no such preset", and `--hdr-weight 1e6`,
// inside the [0, 1e+06] its help states, was refused as "must be >= 0 and finite".
TEST_F(Hostile, Issue51Case24FlagMistakesNameTheFlagAndWhatIsWrong) {
  const std::string train = "train --data " + S() + " --out " + (*this / "X").string();
  for (const auto& [args, flag] : std::vector<std::pair<std::string, std::string>>{
           {train + " --iterations 5 --iterations 6", "--iterations"},
           {train + " --hdr-weight 0.5 --hdr-weight 0.5", "--hdr-weight"},
           {"render --run " + R() + " --threads 1 --threads 2", "--threads"},
           {"bench table ci --store s.db --format md --format csv", "--format"},
           {"dataset preview " + S() + " -o a.png --columns 2 --columns 3", "--columns"}}) {
    ExpectOneLineError(RunHdr4d(args), args, {flag + " was given 2 times; give it once"});
  }
  const fs::path empty = *this / "empty.json";
  testing::WriteTextFile(empty, "");
  testing::WriteTextFile(*this / "notes.txt", "iterations: 3\n");
  for (const auto& [config, what] : std::vector<std::pair<std::string, std::string>>{
           {"/dev/null", "--config /dev/null: is a character device, expected a JSON file"},
           {S(), "--config " + S() + ": is a folder"},
           {empty.string(), "--config " + empty.string() + ": the file is empty"},
           {(*this / "notes.txt").string(), "notes.txt: invalid JSON"}}) {
    const std::string args = train + " --config " + config;
    ExpectOneLineError(RunHdr4d(args), args, {what});
  }
  ExpectOneLineError(RunHdr4d(train + " --hdr-weight 2e6"), "--hdr-weight 2e6",
                     {"--hdr-weight: expected a number in [0, 1e+06], got '2e6'"});
  EXPECT_FALSE(fs::exists(*this / "X"));
  // The range's end is in it: the run trains.
  const auto r = RunHdr4d(train + " --hdr-weight 1e6 --supervision ldr --iterations 1 --threads 1");
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

}  // namespace
}  // namespace hdr4d
