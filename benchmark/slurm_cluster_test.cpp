// `hdr4d bench slurm` against the real scheduler: scripts/local-slurm.sh starts a one-node
// cluster (munged, slurmctld, slurmd on localhost) in a temporary folder, the generated
// submit.sh submits the job arrays with sbatch, the test waits for every array task to leave
// the queue and finish COMPLETED, `hdr4d bench collect` merges the results, and every run's
// metrics are compared with the same suite run locally by `hdr4d bench run`. The daemons are
// stopped whatever happens. Skipped only when Slurm or munge is not installed (Debian:
// apt-get install slurm-wlm munge; scripts/install-deps.sh installs them) or not run as root.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <set>
#include <sstream>
#include <thread>

#include "benchmark/bench_test_util.h"
#include "benchmark/results_store.h"
#include "core/files/json_util.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
namespace fs = std::filesystem;
using namespace testutil;
using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The path of a program on PATH or in the sbin folders (where Debian puts the daemons), or "".
std::string Which(const std::string& program) {
  std::string dirs = std::getenv("PATH") ? std::getenv("PATH") : "";
  dirs += ":/usr/sbin:/sbin";
  std::istringstream in(dirs);
  for (std::string dir; std::getline(in, dir, ':');)
    if (!dir.empty() && access((fs::path(dir) / program).c_str(), X_OK) == 0) return (fs::path(dir) / program).string();
  return "";
}

// A command's exit and its output (each call gets a log file of its own).
struct Output {
  ChildResult result;
  std::string text;
};

bool PortFree(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return false;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_ANY);
  const bool ok = bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  close(fd);
  return ok;
}

// Ports P and P+1 for slurmctld and slurmd: not Slurm's defaults (a Slurm already running here
// is left alone) and free now (another copy of this test may be running).
std::string FreePortPair() {
  for (int p = 16817; p < 17817; p += 10)
    if (PortFree(p) && PortFree(p + 1)) return std::to_string(p);
  return "16817";  // local-slurm.sh then says the port is taken
}

class LocalSlurm {
 public:
  explicit LocalSlurm(const fs::path& dir) : state_(dir / "slurm"), logs_(dir / "commands") {
    fs::create_directories(logs_);
    const char* port = std::getenv("HDR4D_SLURM_PORT");
    port_ = port ? port : FreePortPair();
    const Output start = Script("start");
    started_ = start.result.ok();
    start_text_ = start.text;
  }
  ~LocalSlurm() {
    const Output stop = Script("stop");
    if (!stop.result.ok()) ADD_FAILURE() << "local-slurm.sh stop: " << stop.result.Describe() << "\n" << stop.text;
  }
  LocalSlurm(const LocalSlurm&) = delete;
  LocalSlurm& operator=(const LocalSlurm&) = delete;

  bool started() const { return started_; }
  const std::string& start_text() const { return start_text_; }
  fs::path conf() const { return state_ / "slurm.conf"; }

  // Runs argv with SLURM_CONF pointing at this cluster.
  Output Run(const std::vector<std::string>& argv) {
    const fs::path log = logs_ / ("command_" + std::to_string(++calls_) + ".log");
    Output o;
    o.result = RunChild({.argv = argv, .log = log, .timeout_seconds = 120,
                         .env = {{"SLURM_CONF", conf().string()}, {"HDR4D_SLURM_PORT", port_}}});
    o.text = testing::ReadTextFile(log);
    o.text.erase(0, o.text.find('\n') + 1);  // RunChild's "$ command" line
    return o;
  }

  // The end of a daemon's log, for failure messages.
  std::string Log(const std::string& daemon) const {
    const fs::path f = state_ / "log" / (daemon + ".log");
    if (!fs::exists(f)) return "(no " + f.string() + ")";
    const std::string text = testing::ReadTextFile(f);
    return "---- end of " + f.string() + " ----\n" + text.substr(text.size() - std::min<std::size_t>(text.size(), 3000));
  }

 private:
  Output Script(const std::string& action) {
    return Run({"/bin/bash", (testing::SourceDir() / "scripts" / "local-slurm.sh").string(), action,
                state_.string()});
  }

  fs::path state_, logs_;
  std::string port_, start_text_;
  bool started_ = false;
  int calls_ = 0;
};

// "JobId=12 ArrayJobId=10 ArrayTaskId=1 ... JobState=COMPLETED ..." -> the value of `key`.
std::string Field(const std::string& line, const std::string& key) {
  const std::string spaced = " " + line + " ";
  const std::size_t at = spaced.find(" " + key + "=");
  if (at == std::string::npos) return "";
  const std::size_t from = at + key.size() + 2;
  return spaced.substr(from, spaced.find(' ', from) - from);
}

// metric -> value for every frame of every stored run: "run/frame/metric".
std::map<std::string, double> AllMetrics(const fs::path& store) {
  ResultsStore s(store, false);
  std::map<std::string, double> all;
  for (const std::string& id : s.RunIds("ok"))
    for (const FrameResult& f : s.Frames(id))
      for (const auto& [metric, value] : f.metrics) all[id + "/" + f.frame + "/" + metric] = value;
  return all;
}

TEST(SlurmCluster, ArraysRunUnderRealSlurmAndCollectLikeALocalRun) {
  std::vector<std::string> missing;
  for (const char* p : {"munged", "slurmctld", "slurmd", "sbatch", "squeue", "scontrol"})
    if (Which(p).empty()) missing.push_back(p);
  if (!missing.empty()) {
    std::string list;
    for (const std::string& m : missing) list += " " + m;
    GTEST_SKIP() << "Slurm/munge not installed (missing:" << list
                 << "); apt-get install slurm-wlm munge, or run scripts/install-deps.sh";
  }
  if (geteuid() != 0) GTEST_SKIP() << "a local Slurm needs root (slurmd starts jobs as their owner); run as root";
  const Clock::time_point t0 = Clock::now();
  testing::TempDir dir;
  LocalSlurm slurm(dir.path());
  ASSERT_TRUE(slurm.started()) << "scripts/local-slurm.sh start failed:\n" << slurm.start_text();
  const double start_seconds = SecondsSince(t0);
  std::printf("[ cluster  ] up in %.1f s: %s", start_seconds, slurm.start_text().c_str());

  // Two resource requests (two arrays) when the node has two cores; 2 seeds each.
  const int cpus = std::min(2, static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  const fs::path suite = dir / "suite.json", jobs = dir / "jobs", cache = dir / "cache";
  WriteTinySuite(suite, "slurm-cluster",
                 {{{"name", "hdr4dgs"}, {"train", {{"method", "hdr4dgs"}}}},
                  {{"name", "4dgs"},
                   {"train", {{"method", "4dgs"}}},
                   {"resources", {{"cpus", cpus}, {"memory_gb", 1}, {"minutes", 10}}}}},
                 {0, 1}, 60);
  const int runs = 4, arrays = cpus == 2 ? 2 : 1;
  const fs::path log = dir / "hdr4d.log";
  const Command plan = RunHdr4dArgs({"bench", "slurm", suite.string(), "--out", jobs.string(), "--cache",
                                     cache.string(), "--partition", "local"},
                                    log);
  ASSERT_TRUE(plan.result.ok()) << plan.text;
  ASSERT_NE(plan.text.find(std::to_string(runs) + " runs in " + std::to_string(arrays) + " job array(s)"),
            std::string::npos) << plan.text;

  // submit.sh as a user runs it: one `sbatch --parsable` per array, each printing its job id.
  const Output submit = slurm.Run({"/bin/bash", (jobs / "submit.sh").string()});
  ASSERT_TRUE(submit.result.ok()) << submit.result.Describe() << "\n" << submit.text << slurm.Log("slurmctld");
  std::vector<std::string> ids;
  {
    std::istringstream in(submit.text);
    for (std::string line; std::getline(in, line);)
      if (!line.empty() && std::all_of(line.begin(), line.end(), ::isdigit)) ids.push_back(line);
  }
  ASSERT_EQ(ids.size(), static_cast<std::size_t>(arrays)) << submit.text;
  std::string id_list;
  for (const std::string& id : ids) id_list += (id_list.empty() ? "" : ",") + id;

  // Wait until no task of these arrays is waiting or running: squeue drops a finished task at
  // once or lists it in its final state.
  const Clock::time_point t_submit = Clock::now();
  const double limit = 600;
  const std::set<std::string> ended = {"COMPLETED", "FAILED", "CANCELLED", "TIMEOUT", "NODE_FAIL",
                                       "OUT_OF_MEMORY", "BOOT_FAIL", "DEADLINE", "PREEMPTED"};
  std::string last;
  for (;;) {
    const Output q = slurm.Run({Which("squeue"), "-h", "-r", "-j", id_list, "-o", "%i %T"});
    ASSERT_TRUE(q.result.ok()) << "squeue: " << q.result.Describe() << "\n" << q.text << slurm.Log("slurmctld");
    std::istringstream in(q.text);
    int waiting = 0;
    std::string summary;
    for (std::string line; std::getline(in, line);) {
      const std::size_t space = line.find(' ');
      if (space == std::string::npos) continue;
      waiting += !ended.count(line.substr(space + 1));
      line[space] = ':';  // "12_0:RUNNING"
      summary.append(" ").append(line);
    }
    if (summary != last) {
      std::printf("[ queue %3.0fs]%s\n", SecondsSince(t_submit), summary.c_str());
      std::fflush(stdout);
      last = summary;
    }
    if (waiting == 0) break;
    ASSERT_LT(SecondsSince(t_submit), limit) << "array tasks not ended after " << limit << " s:" << summary
                                             << "\n" << slurm.Log("slurmd");
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  const double queue_seconds = SecondsSince(t_submit);

  // Every array task finished COMPLETED with exit code 0 (scontrol keeps finished jobs for
  // MinJobAge; there is no accounting database for sacct).
  int completed = 0;
  for (const std::string& id : ids) {
    const Output show = slurm.Run({Which("scontrol"), "-o", "show", "job", id});
    ASSERT_TRUE(show.result.ok()) << show.text;
    std::istringstream in(show.text);
    for (std::string line; std::getline(in, line);) {
      if (line.empty()) continue;
      const std::string task = Field(line, "ArrayJobId") + "_" + Field(line, "ArrayTaskId");
      const fs::path out = jobs / "logs" / (task + ".out");
      ASSERT_TRUE(fs::exists(out)) << out << " (the --output of the array script) is missing: " << line;
      const std::string output = testing::ReadTextFile(out);
      EXPECT_EQ(Field(line, "JobState"), "COMPLETED") << task << ": " << line << "\n" << output;
      EXPECT_EQ(Field(line, "ExitCode"), "0:0") << task << ":\n" << output;
      EXPECT_NE(output.find("bench task: "), std::string::npos) << output;
      ++completed;
    }
  }
  EXPECT_EQ(completed, runs);

  const fs::path store = dir / "slurm.db";
  const Command collect = RunHdr4dArgs({"bench", "collect", jobs.string(), "--store", store.string()}, log);
  ASSERT_TRUE(collect.result.ok()) << collect.text;
  EXPECT_NE(collect.text.find(std::to_string(runs) +
                              " runs merged, 0 failed runs merged, 0 already in the store, 0 planned runs without a result"),
            std::string::npos) << collect.text;
  {
    ResultsStore s(store, false);
    EXPECT_EQ(s.RunIds("ok").size(), static_cast<std::size_t>(runs));
    for (const RunSummary& r : s.Summaries()) EXPECT_EQ(r.source, "slurm") << r.run_id;
  }

  // The same suite run here: the same run ids and the same metrics, frame by frame (a seed gives
  // the same bytes at any thread count).
  const fs::path local = dir / "local.db";
  const Command run = RunHdr4dArgs({"bench", "run", suite.string(), "--store", local.string(), "--cache",
                                    cache.string()}, log);
  ASSERT_TRUE(run.result.ok()) << run.text;
  EXPECT_EQ(ResultsStore(local, false).RunIds("ok"), ResultsStore(store, false).RunIds("ok"));
  const std::map<std::string, double> under_slurm = AllMetrics(store), here = AllMetrics(local);
  EXPECT_FALSE(under_slurm.empty());
  EXPECT_EQ(under_slurm, here);
  std::printf("[ timing   ] cluster up %.1f s; %d tasks in %zu array(s), submit to done %.1f s; test %.1f s\n",
              start_seconds, runs, ids.size(), queue_seconds, SecondsSince(t0));
}

}  // namespace
}  // namespace hdr4d::bench
