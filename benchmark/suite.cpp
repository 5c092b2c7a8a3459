#include "benchmark/suite.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <set>

#include "benchmark/names.h"
#include "benchmark/settings_flags.h"
#include "core/files/output_guard.h"
#include "core/util/error.h"
#include "core/files/json_util.h"

#ifndef HDR4D_SOURCE_DIR
#define HDR4D_SOURCE_DIR "."
#endif

namespace hdr4d::bench {
namespace fs = std::filesystem;
namespace {

// The flags the harness sets from the suite's axes and --jobs; settings may not.
const std::vector<std::string> kReservedTrain = {"data",       "out",         "threads",
                                                 "seed",       "iterations",  "max-seconds",
                                                 "supervision", "resume",     "test-every"};
const std::vector<std::string> kReservedRender = {"run", "out", "split", "threads", "timing"};

// A JSON object reader that names the file and the key path in every error and refuses keys
// it does not know ("comment" is allowed anywhere, for notes).
class Obj {
 public:
  Obj(const nlohmann::json& j, std::string where) : j_(j), where_(std::move(where)) {
    if (!j_.is_object()) Fail("{}: expected a JSON object, got {}", where_, Short(j_));
  }
  const std::string& where() const { return where_; }
  std::string At(const std::string& key) const { return where_ + "." + key; }
  bool Has(const std::string& key) const { return j_.contains(key); }
  const nlohmann::json& Raw(const std::string& key) const { return j_.at(key); }

  void OnlyKeys(std::initializer_list<const char*> keys) const {
    for (const auto& item : j_.items()) {
      const std::string& k = item.key();  // not a binding: clang < 16 cannot capture one
      if (k == "comment") continue;
      if (std::none_of(keys.begin(), keys.end(), [&](const char* a) { return k == a; })) {
        std::string known;
        for (const char* a : keys) known += std::string(known.empty() ? "" : ", ") + a;
        Fail("{}: unknown key '{}' (known: {})", where_, k, known);
      }
    }
  }
  std::string String(const std::string& key, const std::string& fallback = "",
                     bool required = false) const {
    if (!Has(key)) {
      if (required) Fail("{}: key '{}' missing", where_, key);
      return fallback;
    }
    if (!j_[key].is_string() || j_[key].get<std::string>().empty())
      Fail("{}: must be a non-empty string, got {}", At(key), Short(j_[key]));
    return j_[key].get<std::string>();
  }
  // A string that names something (benchmark/names.h): never a path.
  std::string Name(const std::string& key, const std::string& fallback = "",
                   bool required = false) const {
    std::string name = String(key, fallback, required);
    RequireName(name, At(key));
    return name;
  }
  double Number(const std::string& key, double fallback, double min) const {
    if (!Has(key)) return fallback;
    if (!j_[key].is_number() || !(j_[key].get<double>() >= min) ||
        !std::isfinite(j_[key].get<double>()))
      Fail("{}: must be a number >= {}, got {}", At(key), min, Short(j_[key]));
    return j_[key].get<double>();
  }
  std::int64_t Integer(const std::string& key, std::int64_t fallback, std::int64_t min) const {
    if (!Has(key)) return fallback;
    if (!j_[key].is_number_integer() || j_[key].get<std::int64_t>() < min)
      Fail("{}: must be an integer >= {}, got {}", At(key), min, Short(j_[key]));
    return j_[key].get<std::int64_t>();
  }
  const nlohmann::json& Array(const std::string& key, bool required) const {
    static const nlohmann::json kEmpty = nlohmann::json::array();
    if (!Has(key)) {
      if (required) Fail("{}: key '{}' missing", where_, key);
      return kEmpty;
    }
    if (!j_[key].is_array() || (required && j_[key].empty()))
      Fail("{}: must be a non-empty JSON array", At(key));
    return j_[key];
  }
  static std::string Short(const nlohmann::json& j) {
    std::string s = j.dump();
    return s.size() > 60 ? s.substr(0, 57) + "..." : s;
  }

 private:
  const nlohmann::json& j_;
  std::string where_;
};

Resources ParseResources(const nlohmann::json& j, const std::string& where, Resources base) {
  const Obj o(j, where);
  o.OnlyKeys({"cpus", "memory_gb", "minutes"});
  base.cpus = static_cast<int>(o.Integer("cpus", base.cpus, 1));
  base.memory_gb = o.Number("memory_gb", base.memory_gb, 0.01);
  base.minutes = o.Number("minutes", base.minutes, 0.01);
  return base;
}

nlohmann::json Settings(const Obj& o, const std::string& key,
                        const std::vector<std::string>& reserved) {
  if (!o.Has(key)) return nlohmann::json::object();
  const nlohmann::json& s = o.Raw(key);
  ValidateSettings(s, reserved, o.At(key));
  return s;
}

std::vector<std::string> Supervisions(const nlohmann::json& list, const std::string& where) {
  std::vector<std::string> out;
  for (const nlohmann::json& s : list) {
    const auto& modes = SupervisionModes();
    if (!s.is_string() || std::find(modes.begin(), modes.end(), s.get<std::string>()) == modes.end())
      Fail("{}: supervision {} is not one of ldr, hdr, ldr+hdr", where, Obj::Short(s));
    out.push_back(s.get<std::string>());
  }
  return out;
}

SceneSpec ParseScene(const nlohmann::json& j, const std::string& where, const fs::path& base) {
  const Obj o(j, where);
  o.OnlyKeys({"name", "group", "path", "datagen", "builtin", "region"});
  SceneSpec s;
  s.name = o.Name("name", "", true);
  s.group = o.Name("group", "syn");
  const int kinds = o.Has("path") + o.Has("datagen") + o.Has("builtin");
  if (kinds != 1) Fail("{}: give exactly one of 'path', 'datagen' or 'builtin'", where);
  if (o.Has("path")) {
    s.kind = SceneSpec::Kind::kPath;
    const fs::path p = o.String("path");
    s.path = p.is_absolute() ? p : fs::absolute(base / p).lexically_normal();
  } else if (o.Has("datagen")) {
    s.kind = SceneSpec::Kind::kDatagen;
    const Obj d(o.Raw("datagen"), o.At("datagen"));
    d.OnlyKeys({"scene", "preset", "seed", "flags"});
    s.source = {{"scene", d.String("scene", "", true)},
                {"preset", d.String("preset", "mini")},
                {"seed", d.Integer("seed", 0, 0)}};
    // More `hdr4d datagen` flags (e.g. a camera pipeline); absent keeps the plain source.
    if (d.Has("flags"))
      s.source["flags"] =
          Settings(d, "flags", {"scene", "preset", "seed", "out", "o", "capture", "list"});
  } else {
    s.kind = SceneSpec::Kind::kBuiltin;
    const Obj b(o.Raw("builtin"), o.At("builtin"));
    b.OnlyKeys({"scene", "flags", "synth"});
    const std::string scene = b.String("scene", "", true);
    if (scene != "demo" && scene != "gaussians")
      Fail("{}: builtin scene '{}' is not demo or gaussians", b.At("scene"), scene);
    if (scene == "gaussians" && b.Has("synth"))
      Fail("{}: the gaussians scene is LDR only; 'synth' does not apply", where);
    s.source = {{"scene", scene},
                {"flags", Settings(b, "flags", {"out", "o"})},
                {"synth", Settings(b, "synth", {"data", "out", "o"})}};
  }
  if (o.Has("region")) {
    const nlohmann::json& r = o.Raw("region");
    if (!r.is_array() || r.size() != 4 ||
        !std::all_of(r.begin(), r.end(), [](const nlohmann::json& v) {
          return v.is_number() && v.get<double>() >= 0 && v.get<double>() <= 1;
        }))
      Fail("{}: must be [x, y, width, height] as fractions of the image in [0, 1]", o.At("region"));
    s.region = std::array<double, 4>{r[0].get<double>(), r[1].get<double>(), r[2].get<double>(),
                                     r[3].get<double>()};
    if ((*s.region)[2] <= 0 || (*s.region)[3] <= 0 || (*s.region)[0] + (*s.region)[2] > 1 ||
        (*s.region)[1] + (*s.region)[3] > 1)
      Fail("{}: the region must have a size and lie inside the image", o.At("region"));
  }
  return s;
}

Budget ParseBudget(const nlohmann::json& j, const std::string& where) {
  const Obj o(j, where);
  o.OnlyKeys({"iterations", "seconds"});
  Budget b;
  b.iterations = o.Integer("iterations", 0, 1);
  b.seconds = o.Number("seconds", 0, 0.001);
  if (b.iterations == 0 && b.seconds == 0)
    Fail("{}: a budget needs 'iterations' and/or 'seconds'", where);
  return b;
}

std::vector<std::int64_t> ParseSeeds(const Obj& o) {
  std::vector<std::int64_t> seeds;
  std::set<std::int64_t> seen;
  const nlohmann::json& list = o.Array("seeds", true);
  if (list.size() > kMaxSuiteRuns)
    Fail("{}: {} seeds; a suite plans at most {} runs", o.At("seeds"), list.size(), kMaxSuiteRuns);
  for (const nlohmann::json& v : list) {
    if (!v.is_number_integer() || v.get<std::int64_t>() < 0)
      Fail("{}: seeds are non-negative integers, got {}", o.At("seeds"), Obj::Short(v));
    if (!seen.insert(v.get<std::int64_t>()).second)
      Fail("{}: seed {} is listed twice", o.At("seeds"), v.get<std::int64_t>());
    seeds.push_back(v.get<std::int64_t>());
  }
  return seeds;
}

std::vector<Budget> ParseBudgets(const Obj& o) {
  std::vector<Budget> out;
  const nlohmann::json& budgets = o.Array("budgets", true);
  std::set<std::string> budget_labels;
  for (std::size_t i = 0; i < budgets.size(); ++i) {
    out.push_back(ParseBudget(budgets[i], fmt::format("{}[{}]", o.At("budgets"), i)));
    if (!budget_labels.insert(out.back().Label()).second)
      Fail("{}: budget {} is listed twice", o.At("budgets"), out.back().Label());
  }
  return out;
}

std::vector<Variant> ParseVariants(const Obj& o) {
  std::vector<Variant> out;
  std::set<std::string> names;
  const nlohmann::json& variants = o.Array("variants", true);
  for (std::size_t i = 0; i < variants.size(); ++i) {
    const Obj v(variants[i], fmt::format("{}[{}]", o.At("variants"), i));
    v.OnlyKeys({"name", "train", "render"});
    Variant var{v.Name("name", "", true), Settings(v, "train", kReservedTrain),
                Settings(v, "render", kReservedRender)};
    if (!names.insert(var.name).second) Fail("{}: variant '{}' twice", v.where(), var.name);
    out.push_back(std::move(var));
  }
  return out;
}

// A method; its resources start from the suite's.
MethodSpec ParseMethod(const nlohmann::json& j,
                       const std::string& where,
                       const Resources& suite_resources) {
  const Obj m(j, where);
  m.OnlyKeys({"name", "label", "supervision", "train", "render", "resources"});
  MethodSpec spec;
  spec.name = m.Name("name", "", true);
  spec.label = m.String("label", spec.name);
  if (m.Has("supervision"))
    spec.supervision = Supervisions(m.Array("supervision", true), m.At("supervision"));
  spec.train = Settings(m, "train", kReservedTrain);
  spec.render = Settings(m, "render", kReservedRender);
  if (m.Has("resources"))
    spec.resources = ParseResources(m.Raw("resources"), m.At("resources"), suite_resources);
  return spec;
}

// A table's rows; rows may name methods outside the suite: external submissions (`bench submit`).
std::vector<TableRow> ParseRows(const Obj& t) {
  std::vector<TableRow> out;
  const nlohmann::json& rows = t.Array("rows", true);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const Obj row(rows[r], fmt::format("{}[{}]", t.At("rows"), r));
    row.OnlyKeys({"label", "method", "supervision"});
    TableRow tr{row.String("label", ""), row.Name("method", "", true),
                row.String("supervision", "", true)};
    if (tr.label.empty()) tr.label = tr.method;
    Supervisions(nlohmann::json::array({tr.supervision}), row.At("supervision"));
    for (const TableRow& other : out)
      if (other.label == tr.label) Fail("{}: row label '{}' twice", t.where(), tr.label);
    out.push_back(std::move(tr));
  }
  return out;
}

TableSpec ParseTable(const nlohmann::json& j, const std::string& where) {
  const Obj t(j, where);
  t.OnlyKeys({"id", "title", "layout", "scenes", "rows", "reference", "note", "finding", "finding_rows"});
  TableSpec spec;
  spec.id = t.Name("id", "", true);
  spec.title = t.String("title", spec.id);
  spec.layout = t.String("layout", "main");
  if (spec.layout != "main" && spec.layout != "ablation")
    Fail("{}: layout '{}' is not main or ablation", t.At("layout"), spec.layout);
  spec.scene_group = t.Name("scenes", "syn");
  spec.note = t.String("note", "");
  spec.finding = t.String("finding", "");
  spec.rows = ParseRows(t);
  spec.reference = t.String("reference", spec.rows.back().label);
  if (std::none_of(spec.rows.begin(), spec.rows.end(),
                   [&](const TableRow& r) { return r.label == spec.reference; }))
    Fail("{}: reference '{}' is not a row label", t.At("reference"), spec.reference);
  if (t.Has("finding_rows")) {
    const nlohmann::json& list = t.Raw("finding_rows");
    if (!list.is_array() || list.empty())
      Fail("{}: must be a non-empty list of row labels, got {}", t.At("finding_rows"), Obj::Short(list));
    for (const nlohmann::json& item : list) {
      if (!item.is_string()) Fail("{}: must hold row labels (strings), got {}", t.At("finding_rows"), Obj::Short(item));
      spec.finding_rows.push_back(item.get<std::string>());
    }
  }
  for (const std::string& label : spec.finding_rows)
    if (label == spec.reference ||
        std::none_of(spec.rows.begin(), spec.rows.end(), [&](const TableRow& r) { return r.label == label; }))
      Fail("{}: '{}' is not a row label other than the reference", t.At("finding_rows"), label);
  return spec;
}

// The runs a suite plans, refused above kMaxSuiteRuns before anything is planned: a dry run of
// 10^6 seeds took 2.6 GB (issue 51, case 24). Counted in doubles: a product of axes cannot wrap.
void RequirePlanSize(const Suite& s, const std::string& where) {
  double per_scene_seed = 0;  // methods x their supervision modes
  for (const MethodSpec& m : s.methods)
    per_scene_seed += static_cast<double>((m.supervision.empty() ? s.supervision : m.supervision).size());
  const double runs = per_scene_seed * static_cast<double>(s.scenes.size()) *
                      static_cast<double>(s.seeds.size()) * static_cast<double>(s.budgets.size()) *
                      static_cast<double>(s.variants.size());
  if (runs > static_cast<double>(kMaxSuiteRuns)) {
    Fail("{}: the suite plans {:.0f} runs ({} method x supervision, {} scenes, {} seeds, {} budgets, "
         "{} variants); a suite plans at most {} runs: split it into smaller suites",
         where, runs, per_scene_seed, s.scenes.size(), s.seeds.size(), s.budgets.size(),
         s.variants.size(), kMaxSuiteRuns);
  }
}

}  // namespace

nlohmann::json Resources::ToJson() const {
  return {{"cpus", cpus}, {"memory_gb", memory_gb}, {"minutes", minutes}};
}

std::string Budget::Label() const {
  std::string label;
  if (iterations > 0) label = fmt::format("{}it", iterations);
  if (seconds > 0) label += fmt::format("{}{}s", label.empty() ? "" : "+", seconds);
  return label;
}

const std::vector<std::string>& SupervisionModes() {
  static const std::vector<std::string> kModes = {"ldr", "hdr", "ldr+hdr"};
  return kModes;
}

const MethodSpec* Suite::FindMethod(const std::string& name) const {
  for (const MethodSpec& m : methods)
    if (m.name == name) return &m;
  return nullptr;
}

const SceneSpec* Suite::FindScene(const std::string& name) const {
  for (const SceneSpec& s : scenes)
    if (s.name == name) return &s;
  return nullptr;
}

Suite ParseSuite(const nlohmann::json& json, const fs::path& file) {
  const std::string where = file.string();
  const Obj o(json, where);
  o.OnlyKeys({"name", "description", "scenes", "methods", "supervision", "seeds", "budgets",
              "variants", "train", "render", "resources", "curve_points", "tables"});
  Suite s;
  s.file = file;
  s.name = o.Name("name", "", true);
  s.description = o.String("description", "");
  s.resources = o.Has("resources") ? ParseResources(o.Raw("resources"), o.At("resources"), {})
                                   : Resources{};
  s.train = Settings(o, "train", kReservedTrain);
  s.render = Settings(o, "render", kReservedRender);
  s.curve_points = static_cast<int>(o.Integer("curve_points", 0, 0));
  if (o.Has("supervision")) s.supervision = Supervisions(o.Array("supervision", true), o.At("supervision"));
  if (o.Has("seeds")) s.seeds = ParseSeeds(o);
  s.budgets = ParseBudgets(o);
  if (o.Has("variants")) s.variants = ParseVariants(o);
  const nlohmann::json& scenes = o.Array("scenes", true);
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    s.scenes.push_back(
        ParseScene(scenes[i], fmt::format("{}[{}]", o.At("scenes"), i), file.parent_path()));
    if (s.FindScene(s.scenes.back().name) != &s.scenes.back())
      Fail("{}: scene '{}' is listed twice", o.At("scenes"), s.scenes.back().name);
  }
  const nlohmann::json& methods = o.Array("methods", true);
  for (std::size_t i = 0; i < methods.size(); ++i) {
    MethodSpec spec =
        ParseMethod(methods[i], fmt::format("{}[{}]", o.At("methods"), i), s.resources);
    if (s.FindMethod(spec.name))
      Fail("{}: method '{}' is listed twice", o.At("methods"), spec.name);
    s.methods.push_back(std::move(spec));
  }
  RequirePlanSize(s, where);
  const nlohmann::json& tables = o.Array("tables", false);
  for (std::size_t i = 0; i < tables.size(); ++i) {
    const std::string at = fmt::format("{}[{}]", o.At("tables"), i);
    TableSpec spec = ParseTable(tables[i], at);
    for (const TableSpec& other : s.tables)
      if (other.id == spec.id) Fail("{}: table id '{}' twice", at, spec.id);
    s.tables.push_back(std::move(spec));
  }
  return s;
}

fs::path SuitesDir() {
  if (const char* dir = std::getenv("HDR4D_SUITES_DIR"); dir && *dir) return dir;
  return fs::path(HDR4D_SOURCE_DIR) / "benchmark" / "suites";
}

Suite LoadSuite(const std::string& name_or_path) {
  fs::path file = name_or_path;
  const bool looks_like_path = name_or_path.find('/') != std::string::npos ||
                               file.extension() == ".json";
  if (!looks_like_path) file = SuitesDir() / (name_or_path + ".json");
  if (!fs::exists(file)) {
    if (looks_like_path) Fail("{}: no such suite file", file.string());
    std::string known;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(SuitesDir(), ec))
      if (e.path().extension() == ".json") known += " " + e.path().stem().string();
    Fail("no suite '{}' (a suite file, or one of the shipped suites in {}:{})", name_or_path,
         SuitesDir().string(), known);
  }
  // Every command that reads a suite leaves it as it was (issue 51, case 1).
  ProtectInputFile(file, "the suite file " + file.string() + " (an input of this command)");
  return ParseSuite(ReadJsonFile(file), fs::absolute(file));
}

}  // namespace hdr4d::bench
