// The stress suite's toolkit (benchmark/stress.h): running hdr4d on a case's inputs, building
// small scenes, and the four checks every case reports.
#pragma once

#include <atomic>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "benchmark/child_process.h"
#include "benchmark/results_store.h"
#include "benchmark/stress.h"
#include "core/dataset/dataset.h"

namespace hdr4d::bench::stress {

inline constexpr const char* kNoCrash = "no crash";
inline constexpr const char* kNoNaN = "no NaN";
inline constexpr const char* kClearError = "clear error";
inline constexpr const char* kNothingLost = "nothing lost";

struct Ctx {
  std::filesystem::path dir;  // this case's folder
  std::string hdr4d;
  int threads = 0;
};

struct Exec {
  ChildResult r;
  std::string text;  // what the command printed
};

std::string ReadText(const std::filesystem::path& p);
// Runs `hdr4d <args>` with its output in a numbered log in the case's folder.
Exec Hdr4d(const Ctx& c, std::vector<std::string> args, const std::atomic<bool>* cancel = nullptr,
           int stop_signal = 15);
// Ended by itself with exit code 0 or 1: no signal, no abort.
bool NoCrash(const ChildResult& r);
// Exit code 1, exactly one "hdr4d: error:" line, naming `file`, and no sign of an abort.
bool ClearError(const Exec& e, const std::string& file);
std::string Short(const Exec& e);

// A small built-in scene: 24 px, 3 cameras (the last held out), 3 timestamps, LDR at the
// given exposures through the filmic response with noise.
void MakeScene(const Ctx& c, const std::filesystem::path& dir, std::vector<std::string> flags,
               bool synth = true);
std::vector<std::string> TrainArgs(const Ctx& c, const std::filesystem::path& scene,
                                   const std::filesystem::path& run, std::vector<std::string> extra);
// Valid input: train, render the test split, score it. Fills "no crash" and "no NaN".
StressOutcome TrainRenderScore(const Ctx& c, const std::filesystem::path& scene,
                               std::vector<std::string> extra);
// Invalid input: `args` must fail with a clear error naming `file`.
StressOutcome ExpectError(const Ctx& c, const std::vector<std::string>& args, const std::string& file);

void ScaleRadiance(const std::filesystem::path& scene, double k);
const Frame& FirstTrainFrame(const std::filesystem::path& scene);
void WritePixel(const std::filesystem::path& exr, float value);
void Truncate(const std::filesystem::path& file, double keep);

using CaseFn = std::function<StressOutcome(const Ctx&)>;
struct Case {
  StressCaseInfo info;
  CaseFn run;
};
// Every case, in the order they run (stress_cases.cpp; the cases by category in
// stress_cases_*.cpp).
std::vector<Case> Cases();

}  // namespace hdr4d::bench::stress
