#include "benchmark/bench_test_util.h"

#include <fstream>
#include <sstream>

#include "core/files/json_util.h"

namespace hdr4d::bench::testutil {
namespace fs = std::filesystem;

fs::path Hdr4d() { return HDR4D_BINARY_PATH; }

fs::path Artifacts(const std::string& name) {
  const fs::path dir = fs::path(HDR4D_TEST_ARTIFACTS) / name;
  fs::create_directories(dir);
  return dir;
}

Command RunHdr4dArgs(const std::vector<std::string>& args, const fs::path& log, double timeout,
                     const std::atomic<bool>* cancel, int stop_signal) {
  std::vector<std::string> argv = {Hdr4d().string()};
  argv.insert(argv.end(), args.begin(), args.end());
  std::error_code ec;
  const auto before = fs::exists(log) ? fs::file_size(log, ec) : 0;
  Command c;
  c.result = RunChild({.argv = argv, .log = log, .timeout_seconds = timeout, .cancel = cancel,
                       .stop_signal = stop_signal});
  std::ifstream in(log);
  in.seekg(static_cast<std::streamoff>(before));
  std::ostringstream s;
  s << in.rdbuf();
  c.text = s.str();
  return c;
}

void WriteTinySuite(const fs::path& path, const std::string& name, const nlohmann::json& methods,
                    const std::vector<int>& seeds, int iterations) {
  WriteJsonFile(path, {{"name", name},
                       {"scenes", {{{"name", "tiny"},
                                    {"builtin",
                                     {{"scene", "demo"},
                                      {"flags", {{"size", 24}, {"timestamps", 3}, {"cameras", 3}, {"spp", 1}}},
                                      {"synth", {{"crf", "filmic"}, {"seed", 1}}}}}}}},
                       {"methods", methods},
                       {"seeds", seeds},
                       {"budgets", {{{"iterations", iterations}}}},
                       {"resources", {{"cpus", 1}, {"memory_gb", 1}, {"minutes", 5}}}});
}

int CountLines(const std::string& text, const std::string& prefix) {
  std::istringstream in(text);
  int n = 0;
  for (std::string line; std::getline(in, line);) n += line.rfind(prefix, 0) == 0;
  return n;
}

}  // namespace hdr4d::bench::testutil
