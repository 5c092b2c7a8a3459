// Benchmark suites: JSON files naming methods x scenes x supervision modes x seeds x budgets
// (x variants), the settings passed to `hdr4d train` / `hdr4d render`, the resources a run
// needs and the tables to print. The format is documented in benchmark/suites/README.md; every
// key is checked, and an unknown key or a bad value is an error naming the file and the key.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace hdr4d::bench {

// What one run may use; a Slurm array asks for it, the harness enforces the time limit.
struct Resources {
  int cpus = 2;
  double memory_gb = 4;
  double minutes = 60;  // wall-clock limit of one run (training, render and scoring)
  nlohmann::json ToJson() const;
};

// Training budget: iterations and/or wall-clock seconds of the training loop (whichever ends
// first; 0 = no limit of that kind, not both 0).
struct Budget {
  std::int64_t iterations = 0;
  double seconds = 0;
  std::string Label() const;  // "3000it", "600s", "3000it+600s"
};

// One point of a settings sweep (e.g. render settings that trade speed for quality).
struct Variant {
  std::string name;  // "" for the suite's default (no sweep)
  nlohmann::json train = nlohmann::json::object(), render = nlohmann::json::object();
};

struct SceneSpec {
  enum class Kind { kPath, kDatagen, kBuiltin };
  std::string name;           // label in tables
  std::string group = "syn";  // tables select scenes by group
  Kind kind = Kind::kPath;
  std::filesystem::path path;  // kPath: absolute
  // kDatagen: {"scene", "preset", "seed"} and optionally "flags" (more datagen flags, such as
  // {"pipeline": "phone"}); kBuiltin: {"scene": "demo"|"gaussians", "flags":
  // {...}, "synth": {...}} (flags of make-demo-scene / make-gaussian-scene and synth-ldr).
  nlohmann::json source = nlohmann::json::object();
  // Region (fractions x, y, width, height of the image) whose luminance over time the report
  // plots; unset: chosen from the ground truth (the most variable cell).
  std::optional<std::array<double, 4>> region;
};

struct MethodSpec {
  std::string name;   // unique in the suite; what tables and the store call it
  std::string label;  // shown in tables (default: name)
  std::vector<std::string> supervision;  // empty: the suite's
  nlohmann::json train = nlohmann::json::object(), render = nlohmann::json::object();
  std::optional<Resources> resources;  // default: the suite's
};

struct TableRow {
  std::string label, method, supervision;
};

struct TableSpec {
  std::string id, title;
  std::string layout = "main";  // "main" (Tables 1-2) or "ablation" (Tables 4-7)
  std::string scene_group = "syn";
  std::vector<TableRow> rows;
  std::string reference;  // row label the paired tests compare with (default: the last row)
  std::string note;
  // The paper's finding the table tests, in words (`bench findings`; "" = "<reference> beats
  // each other row"). A main table takes part in `bench findings` only when it words one.
  std::string finding;
  // The rows the finding compares the reference with (empty: every other row); a main table
  // leaves out the paper's own variants this way (Table 1's HDR-4DGS† is no baseline).
  std::vector<std::string> finding_rows;
};

struct Suite {
  std::string name, description;
  std::filesystem::path file;
  std::vector<SceneSpec> scenes;
  std::vector<MethodSpec> methods;
  std::vector<std::string> supervision = {"ldr"};
  std::vector<std::int64_t> seeds = {0};
  std::vector<Budget> budgets;
  std::vector<Variant> variants = {Variant{}};
  nlohmann::json train = nlohmann::json::object(), render = nlohmann::json::object();
  Resources resources;
  int curve_points = 0;  // test evaluations during training (the PSNR curve); 0 = none
  std::vector<TableSpec> tables;

  const MethodSpec* FindMethod(const std::string& name) const;
  const SceneSpec* FindScene(const std::string& name) const;
};

// The most runs one suite may plan (methods x supervision x scenes x seeds x budgets x
// variants); the shipped suites plan at most 792. A larger suite is refused when it is read.
inline constexpr std::size_t kMaxSuiteRuns = 10000;

// Parses a suite; relative scene paths are taken from the suite file's folder.
Suite ParseSuite(const nlohmann::json& json, const std::filesystem::path& file);
// `name_or_path`: a file, or the name of a shipped suite (benchmark/suites/<name>.json, or
// $HDR4D_SUITES_DIR/<name>.json). Throws hdr4d::Error naming the file and the problem.
Suite LoadSuite(const std::string& name_or_path);
// The folder of the shipped suites.
std::filesystem::path SuitesDir();

// Supervision modes a run may use.
const std::vector<std::string>& SupervisionModes();  // ldr, hdr, ldr+hdr

}  // namespace hdr4d::bench
