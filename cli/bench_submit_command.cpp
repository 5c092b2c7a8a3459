// `hdr4d bench submit`: an external method's renders scored into a store (benchmark/submit.h).
#include <fmt/format.h>

#include <cstdint>
#include <limits>
#include <memory>
#include <string>

#include "benchmark/run_record.h"
#include "benchmark/submit.h"
#include "cli/bench_commands.h"
#include "cli/flags.h"

namespace hdr4d::cli {

void AddBenchSubmit(CLI::App& bench) {
  auto o = std::make_shared<bench::SubmitOptions>();
  CLI::App* cmd = bench.add_subcommand(
      "submit",
      "Score a folder of renders from any method (named like the ground truth: each test "
      "frame's file_path as PNG, its exr_file_path as EXR) into the store, so external methods "
      "sit in the same tables. Missing or extra frames, wrong sizes and NaN pixels are errors; "
      "a submission never changes another run's rows.");
  cmd->add_option("--store", o->store, "Results store")->required()
      ->check(Text("a results store"));
  cmd->add_option("--method", o->method, "Method name in the tables")->required()
      ->check(Text("a method name"));
  cmd->add_option("--scene", o->scene, "Dataset folder, or a scene name of --suite")->required()
      ->check(Text("a dataset folder or scene name"));
  cmd->add_option("--renders", o->renders, "Folder of renders")->required()
      ->check(Text("a folder of renders"));
  cmd->add_option("--suite", o->suite, "Suite whose tables the submission joins (and whose scene --scene names)")
      ->check(Text("a suite file or shipped suite name"));
  cmd->add_option("--meta", o->meta, "JSON with train_seconds, render_fps, gaussians, peak_rss_mb, iterations, code_version, machine, notes")
      ->check(Text("a JSON file"));
  cmd->add_option("--supervision", o->supervision, "ldr, hdr or ldr+hdr")->capture_default_str()
      ->check(OneOf({"ldr", "hdr", "ldr+hdr"}));
  cmd->add_option("--seed", o->seed, "Seed of the submitted run")->capture_default_str()
      ->check(Integer(0, std::numeric_limits<std::int64_t>::max()));
  cmd->add_option("--cache", o->cache_dir, "Scene cache (for suite scenes)")
      ->check(Text("a scene cache folder"));
  cmd->add_flag("--replace", o->replace, "Replace an earlier submission of this method, scene, supervision and seed");
  cmd->callback([o] {
    const bench::RunRecord r = bench::Submit(*o);
    fmt::print("bench submit: {} on {}: {} frames scored, stored as run {}\n", o->method,
               r.labels.front().scene, r.frames.size(), r.id);
  });
}

}  // namespace hdr4d::cli
