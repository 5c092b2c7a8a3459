#include "method/train/resume_check.h"

#include <string>

#include "core/util/error.h"
#include "core/files/json_util.h"
#include "method/train/train_options_table.h"

namespace hdr4d::method {
namespace fs = std::filesystem;

namespace {

std::string Short(const nlohmann::json& v) {
  std::string text = v.dump();
  if (text.size() > 80) text = text.substr(0, 77) + "...";
  return text;
}

fs::path Canonical(const std::string& path) {
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(path, ec);
  return ec ? fs::path(path).lexically_normal() : p;
}

// What is compared: a resume's options (all, or only those given) with the run's record, or the
// record in config.json with the one its checkpoint was trained with (`checkpoint` is then set).
struct Comparison {
  const fs::path& config_file;
  bool given_only = false;
  const fs::path* checkpoint = nullptr;
};

[[noreturn]] void FailDropped(const Comparison& c, const std::string& key,
                              const nlohmann::json& value) {
  if (c.checkpoint) {
    Fail("{}: has no {}, but {} was trained with {} = {}: the run's files do not belong together "
         "(config.json edited, or another run's checkpoint); put back the run's own",
         c.config_file.string(), key, c.checkpoint->string(), key, Short(value));
  }
  Fail("{}: --resume would drop the run's {} = {} (start a new run folder to change the "
       "configuration)",
       c.config_file.string(), key, Short(value));
}

[[noreturn]] void FailDiffers(const Comparison& c, const std::string& key,
                              const nlohmann::json& saved, const nlohmann::json& requested) {
  if (c.checkpoint) {
    Fail("{}: {} = {}, but {} was trained with {}: the run's files do not belong together "
         "(config.json edited, or another run's checkpoint); put back the run's own",
         c.config_file.string(), key, Short(requested), c.checkpoint->string(), Short(saved));
  }
  Fail("{}: --resume with {} = {}, but the run was started with {}; a resumed run keeps its "
       "configuration (start a new run folder to change it)",
       c.config_file.string(), key, Short(requested), Short(saved));
}

// Depth is bounded by the configuration's own shape (a few levels): it is our file.
// given_only: compare the keys `requested` holds, never asking for the others.
void Compare(const nlohmann::json& saved,
             const nlohmann::json& requested,
             const std::string& key,
             const Comparison& c) {
  if (MayChangeOnResume(key)) return;  // the option table says which (train_options_table.h)
  // The scene may move after training; data_checksums.json says whether it is the same one.
  if (c.checkpoint && key == "data") return;
  if (saved.is_object() && requested.is_object()) {
    for (const auto& [name, value] : saved.items()) {
      const std::string sub = key.empty() ? name : key + "." + name;
      const auto it = requested.find(name);
      if (it == requested.end()) {
        if (MayChangeOnResume(sub) || c.given_only || (c.checkpoint && sub == "data")) continue;
        FailDropped(c, sub, value);
      }
      Compare(value, *it, sub, c);
    }
    return;
  }
  if (key == "data" && saved.is_string() && requested.is_string()) {
    if (Canonical(saved.get<std::string>()) == Canonical(requested.get<std::string>())) return;
  } else if (saved == requested) {
    return;
  }
  FailDiffers(c, key, saved, requested);
}

}  // namespace

nlohmann::json ReadSavedRunConfig(const fs::path& run) {
  const fs::path file = run / "config.json";
  std::error_code ec;
  if (!fs::exists(file, ec))
    Fail("{}: not found: no run here to resume from its checkpoint (train without --resume to "
         "start one)",
         file.string());
  nlohmann::json config = ReadJsonFile(file);
  if (!config.is_object()) Fail("{}: not a run configuration (expected a JSON object)", file.string());
  // A start that failed before its first checkpoint (killed early, a full disk) has nothing to
  // continue from: say so, not "checkpoint not found" (issue 51 §20).
  if (!fs::exists(run / "checkpoint.bin", ec) && !fs::is_symlink(run / "checkpoint.bin", ec))
    Fail("{}: the run has a configuration but no checkpoint.bin: it stopped before its first "
         "checkpoint was written (killed early, or a write failed, e.g. a full disk), so there is "
         "nothing to resume; start it again with --overwrite instead of --resume",
         run.string());
  return config;
}

void KeepSavedSchedules(const nlohmann::json& saved, OptimizationOptions* requested) {
  const auto it = saved.find("optimization");
  if (it == saved.end() || !it->is_object()) return;
  const std::string prefix = "optimization.";
  TrainOptions options;
  options.optimization = *requested;
  // The rows whose negative value follows the run length (or the scene): densify_from, ...
  for (const TrainOption& row : TrainOptionTable()) {
    if (row.unset != Unset::kNegative || row.key.rfind(prefix, 0) != 0) continue;
    if (row.get(options).get<double>() >= 0) continue;  // given explicitly
    const auto v = it->find(row.key.substr(prefix.size()));
    if (v != it->end() && v->is_number() && v->get<double>() >= 0) row.set(&options, *v);
  }
  // The many-view schedule's switch: what the run decided (a run from before it: off).
  if (!options.optimization.clone_opacity_correction) {
    const auto v = it->find("clone_opacity_correction");
    options.optimization.clone_opacity_correction =
        v != it->end() && v->is_boolean() && v->get<bool>();
  }
  *requested = options.optimization;
}

bool AcceptAddedHdrHead(nlohmann::json* saved, const nlohmann::json& requested_hdr) {
  const auto hdr = saved->find("hdr");
  if (hdr == saved->end() || !hdr->is_object()) return false;
  const auto is = [](const nlohmann::json& j, const char* key, const nlohmann::json& value) {
    const auto it = j.find(key);
    return it != j.end() && *it == value;
  };
  if (!is(*hdr, "supervision", "ldr") || is(*hdr, "hdr_head", true)) return false;
  if (!is(requested_hdr, "hdr_head", true) || !is(requested_hdr, "supervision", "ldr+hdr"))
    return false;
  (*hdr)["supervision"] = requested_hdr["supervision"];
  (*hdr)["hdr_head"] = true;
  if (const auto it = requested_hdr.find("hdr_head_iterations"); it != requested_hdr.end())
    (*hdr)["hdr_head_iterations"] = *it;
  if (const auto r = saved->find("resolved"); r != saved->end() && r->is_object())
    (*r)["hdr_head"] = true;
  return true;
}

void RequireSameConfig(const nlohmann::json& saved,
                       const nlohmann::json& requested,
                       const fs::path& config_file) {
  Compare(saved, requested, "", {.config_file = config_file});
}

void RequireSameGivenConfig(const nlohmann::json& saved,
                            const nlohmann::json& requested,
                            const fs::path& config_file) {
  Compare(saved, requested, "", {.config_file = config_file, .given_only = true});
}

void RequireCheckpointOfThisConfig(const nlohmann::json& trainer,
                                   const nlohmann::json& config,
                                   const fs::path& config_file,
                                   const fs::path& checkpoint_file) {
  const auto it = trainer.find(kRunConfigKey);
  if (it == trainer.end()) return;  // a run from before the record
  if (!it->is_object())
    Fail("{}: corrupt checkpoint: its {} is not an object", checkpoint_file.string(), kRunConfigKey);
  if (!config.is_object())
    Fail("{}: not a run configuration (expected a JSON object)", config_file.string());
  nlohmann::json trained = *it;
  // A resume that added --hdr-head rewrote config.json before its first checkpoint.
  if (const auto hdr = config.find("hdr"); hdr != config.end() && hdr->is_object())
    AcceptAddedHdrHead(&trained, *hdr);
  Compare(trained, config, "", {.config_file = config_file, .checkpoint = &checkpoint_file});
}

}  // namespace hdr4d::method
