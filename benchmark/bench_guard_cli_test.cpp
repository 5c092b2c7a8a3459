// Issue 51, cases 1 and 10: the bench commands register what they read (the store, the suite)
// with the output guard, and never write into a dataset's image folders, also when they read no
// dataset: `bench report S --store y.db --out y.db` turned the store into an HTML page, and
// `bench table --out SCENE/images` wrote among the ground truth.
#include <gtest/gtest.h>

#include "benchmark/bench_test_util.h"
#include "benchmark/results_store.h"
#include "benchmark/suite.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
namespace fs = std::filesystem;
using namespace testutil;

// Every file under `root` with its size and modification time.
std::map<std::string, std::pair<std::uintmax_t, fs::file_time_type>> Listing(const fs::path& root) {
  std::map<std::string, std::pair<std::uintmax_t, fs::file_time_type>> files;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (e.is_regular_file()) files[e.path().string()] = {e.file_size(), e.last_write_time()};
  }
  return files;
}

TEST(BenchGuard, BenchCommandsNeverWriteOverTheirInputsNorIntoADataset) {
  testing::TempDir dir, logs;  // the commands' log outside the folder compared
  const fs::path store = dir / "y.db", scene = dir / "S", log = logs / "log.txt";
  { ResultsStore created(store, true); }
  const fs::path suite = dir / "s.json";
  fs::copy_file(SuitesDir() / "ci.json", suite);
  ASSERT_TRUE(RunHdr4dArgs({"make-demo-scene", "--out", scene.string(), "--cameras", "2", "--size",
                            "16", "--timestamps", "2", "--spp", "1"},
                           log)
                  .result.ok());
  const auto before = Listing(dir.path());
  const std::vector<std::vector<std::string>> cases = {
      {"bench", "report", suite.string(), "--store", store.string(), "--out", store.string()},
      {"bench", "report", suite.string(), "--store", store.string(), "--out", suite.string()},
      {"bench", "report", suite.string(), "--store", store.string(), "--out", (scene / "hdr" / "r.html").string()},
      {"bench", "table", suite.string(), "--store", store.string(), "--out", (scene / "hdr").string()},
      {"bench", "pareto", suite.string(), "--store", store.string(), "--out", (scene / "hdr").string()},
  };
  for (const auto& args : cases) {
    const Command c = RunHdr4dArgs(args, log);
    EXPECT_EQ(c.result.exit_code, 1) << args[1] << " " << args.back() << "\n" << c.text;
    EXPECT_NE(c.text.find("refusing to write"), std::string::npos) << args.back() << "\n" << c.text;
  }
  EXPECT_EQ(Listing(dir.path()), before);
}

}  // namespace
}  // namespace hdr4d::bench
