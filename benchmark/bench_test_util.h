// Helpers of the harness's end-to-end tests: running the hdr4d binary with an argument list
// (and killing it), a folder of test artifacts that outlives the test (the ci store, the
// report's screenshot), tiny suites written on the fly.
#pragma once

#include <atomic>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "benchmark/child_process.h"

namespace hdr4d::bench::testutil {

std::filesystem::path Hdr4d();
// build/test_artifacts/<name>, created.
std::filesystem::path Artifacts(const std::string& name);

struct Command {
  ChildResult result;
  std::string text;  // stdout and stderr together
};
Command RunHdr4dArgs(const std::vector<std::string>& args, const std::filesystem::path& log,
                     double timeout_seconds = 0, const std::atomic<bool>* cancel = nullptr,
                     int stop_signal = 15);

// A suite on the built-in demo scene (24 px, 3 cameras, 3 timestamps) with these methods
// ({"name": ..., "train": {...}}), seeds and iterations, written to `path`.
void WriteTinySuite(const std::filesystem::path& path, const std::string& name,
                    const nlohmann::json& methods, const std::vector<int>& seeds, int iterations);

// Lines of `text` that start with `prefix`.
int CountLines(const std::string& text, const std::string& prefix);

}  // namespace hdr4d::bench::testutil
