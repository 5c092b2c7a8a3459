// hdr4d train: HDR-4DGS (or one of the paper's baselines) on a dataset. The options are the rows
// of method/train/train_options_table.h, each added here as a flag with its help and its
// range; the few flags that are not options of the run (--out, --resume, --config,
// --list-configs, --method) are added by hand.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <memory>
#include <string>
#include <vector>

#include "baselines/scene_baselines.h"
#include "cli/commands.h"
#include "cli/flags.h"
#include "cli/train_hexplane.h"
#include "method/train/train_config.h"
#include "method/train/train_options_table.h"
#include "method/train/run_folder.h"
#include "method/train/train_request.h"
#include "method/train/trainer.h"

namespace hdr4d::cli {
namespace {

using method::OptionType;
using method::TrainOption;

// `hdr4d train --list-configs`: every preset with its values, then the keys of a file.
void ListTrainConfigs() {
  for (const method::TrainPreset& p : method::TrainPresets())
    fmt::print("{:<20} {}\n{:<20} {}\n", p.name, p.what, "", p.values.dump());
  std::vector<std::string> keys;
  for (const method::TrainConfigKey& k : method::TrainConfigKeys()) {
    keys.push_back(k.flag.empty() ? fmt::format("{}: {}", k.name, k.accepts)
                                  : fmt::format("{} ({}): {}", k.name, k.flag, k.accepts));
  }
  fmt::print("\nA --config FILE is a JSON object with any of these keys (flag that wins over it):\n"
             "  {}\n",
             fmt::join(keys, "\n  "));
}

// One row of the option table on the command line: its text as given (a switch: whether it was
// on), checked by CLI11 against the row's range or choices before anything runs.
struct TableFlag {
  const TrainOption* option = nullptr;
  CLI::Option* cli = nullptr;
  std::string text;
  bool on = false;
};

CLI::Validator RowValidator(const TrainOption& row) {
  switch (row.type) {
    case OptionType::kUint64:
      return Seed();
    case OptionType::kText:
      return row.choices ? OneOf(row.choices()) : Text(row.what);
    default:
      break;
  }
  if (!row.accepts_auto) return InRange(row.range);
  // A number of the range, or the word auto (--iterations auto).
  const CLI::Validator number = InRange(row.range);
  return CLI::Validator(
      [number](std::string& text) -> std::string {
        if (text == "auto") return "";
        std::string problem = number(text);
        return problem.empty() ? "" : problem + " or auto";
      },
      number.get_description() + " or auto", "number or auto");
}

// The text converted to the member's type exactly as CLI11 converts it into a variable of that
// type, as JSON of the type.
template <typename T>
nlohmann::json Converted(const std::string& text) {
  T value{};
  CLI::detail::lexical_cast(text, value);
  return nlohmann::json(value);
}

nlohmann::json GivenValue(const TableFlag& f) {
  if (f.option->accepts_auto && f.text == "auto") return nlohmann::json("auto");
  switch (f.option->type) {
    case OptionType::kBool:
      return f.option->SwitchValue(/*off=*/!f.on);
    case OptionType::kInt:
      return Converted<int>(f.text);
    case OptionType::kInt64:
      return Converted<std::int64_t>(f.text);
    case OptionType::kUint64:
      return Converted<std::uint64_t>(f.text);
    case OptionType::kDouble:
      return Converted<double>(f.text);
    case OptionType::kFloat:
      return Converted<float>(f.text);
    default:
      return nlohmann::json(f.text);
  }
}

// "[20000]" in the help: the member's default as CLI11 prints a variable of its type.
std::string DefaultText(const TrainOption& row) {
  method::TrainOptions defaults;
  defaults.hdr.tone_mapper.emplace();  // the tone-mapper options' defaults
  const nlohmann::json v = row.get(defaults);
  switch (row.type) {
    case OptionType::kInt:
      return CLI::detail::to_string(v.get<int>());
    case OptionType::kInt64:
      return CLI::detail::to_string(v.get<std::int64_t>());
    case OptionType::kUint64:
      return CLI::detail::to_string(v.get<std::uint64_t>());
    case OptionType::kDouble:
      return CLI::detail::to_string(v.get<double>());
    case OptionType::kFloat:
      return CLI::detail::to_string(v.get<float>());
    default:
      return v.is_string() ? v.get<std::string>() : v.dump();
  }
}

// CLI11's own name of a variable of the member's type, as the help showed it.
const char* TypeName(OptionType type) {
  switch (type) {
    case OptionType::kInt:
    case OptionType::kInt64:
      return "INT";
    case OptionType::kUint64:
      return "UINT";
    case OptionType::kDouble:
    case OptionType::kFloat:
      return "FLOAT";
    default:
      return "TEXT";
  }
}

void AddTableFlag(CLI::App* cmd, const TrainOption& row, TableFlag* f) {
  f->option = &row;
  if (row.type == OptionType::kBool) {
    const std::string names = row.off_flag.empty() ? row.flag : row.flag + ",!" + row.off_flag;
    f->cli = cmd->add_flag(names, f->on, row.help);
    return;
  }
  f->cli = cmd->add_option(row.flag, f->text, row.help)
               ->type_name(TypeName(row.type))
               ->check(RowValidator(row));
  if (row.show_default) f->cli->default_str(DefaultText(row));
}

// The flags of the options a resumed run may change, for --resume's help.
std::string MayChangeOnResumeFlags() {
  std::vector<std::string> flags;
  for (const TrainOption& row : method::TrainOptionTable())
    if (row.may_change_on_resume && !row.flag.empty()) flags.push_back(row.flag);
  if (flags.size() < 2) return fmt::format("{}", fmt::join(flags, ""));
  const std::string last = flags.back();
  flags.pop_back();
  return fmt::format("{} and {}", fmt::join(flags, ", "), last);
}

struct TrainArgs {
  method::TrainRequest request;
  std::string out, method = "hdr4dgs";
  bool list_configs = false;
  CLI::Option* method_flag = nullptr;
  std::vector<TableFlag> flags;
  CLI::App* cmd = nullptr;  // the grid family reads its shared flags from it
  std::shared_ptr<baselines::hexplane::HexPlaneTrainOptions> hexplane;
};

void AddRunFlags(CLI::App* cmd, TrainArgs* a) {
  cmd->add_option("--out", a->out, "Run folder")->check(Text("a run folder"));
  cmd->add_option("--config", a->request.config,
                  "Training configuration: a JSON file of option names and values "
                  "(iterations, batch_size, resolution, max_gaussians, densify_until, ...) or a "
                  "preset of the reference's per-scene settings (syn/lego, real/bed, dnerf/trex, "
                  "...; --list-configs). A flag given here wins over it; RUN/config.json keeps "
                  "the resolved values")
      ->check(Text("a configuration file or preset name"));
  cmd->add_flag("--list-configs", a->list_configs,
                "List the presets of --config with their values and the keys a file may hold, "
                "then exit");
  cmd->add_flag("--resume", a->request.resume,
                "Continue from RUN/checkpoint.bin, exactly as if never stopped, with the run's "
                "own configuration (RUN/config.json): --data and every option not given come "
                "from it; an option given that differs from it is refused before the scene is "
                "read, except " + MayChangeOnResumeFlags());
  cmd->add_flag("--overwrite", a->request.overwrite, method::OverwriteHelp())
      ->excludes("--resume");
  a->method_flag =
      cmd->add_option(
             "--method", a->method,
             fmt::format("Method of the paper's tables: {} (default hdr4dgs; 4dgs when every "
                         "training image has one exposure and the scene has no HDR ground truth, "
                         "with a note: there is no HDR to recover)",
                         fmt::join(TrainMethodNames(), ", ")))
          ->check(OneOf(TrainMethodNames()))
          ->capture_default_str();
}

void RunTrain(TrainArgs& a) {
  if (a.list_configs) {
    ListTrainConfigs();
    return;
  }
  if (TrainHexPlaneIfAsked(a.cmd, a.method, *a.hexplane)) return;  // the grid family
  method::TrainRequest& request = a.request;
  request.out = a.out;
  request.default_method = "hdr4dgs";
  if (a.method_flag->count() > 0) request.method = a.method;
  for (const TableFlag& f : a.flags) {
    // Given or not is told by the flag's count, never by a sentinel value a user could type.
    if (f.cli->count() == 0 || (f.option->off_flag.empty() && f.option->type == OptionType::kBool && !f.on))
      continue;
    request.given.push_back({f.option, GivenValue(f)});
  }
  const method::TrainSummary s =
      method::Train(method::ResolveTrainRequest(request, baselines::MethodPreset));
  const std::string kept =
      s.model_iteration > 0 && s.model_iteration != s.iterations
          ? fmt::format(" (kept: the model of iteration {}, the best val evaluation)",
                        s.model_iteration)
          : "";
  fmt::print("train: {} iterations in {:.1f} s{}, {} Gaussians; test {}\n", s.iterations,
             s.train_seconds, kept, s.gaussians, s.test_metrics.dump());
}

}  // namespace

void AddTrainCommand(CLI::App& app) {
  auto args = std::make_shared<TrainArgs>();
  CLI::App* cmd = app.add_subcommand(
      "train",
      "Train HDR-4DGS (log-HDR 4D Gaussians + the Dynamic Tone Mapper) or one of the paper's "
      "baselines on a scene (a static scene trains without the time axis). Writes "
      "RUN/config.json, RUN/checkpoint.bin and RUN/results.json (test metrics with the keys of "
      "`hdr4d eval`, LDR and HDR, training seconds, iterations, Gaussian count).");
  const std::vector<TrainOption>& table = method::TrainOptionTable();
  args->flags.reserve(table.size());  // CLI11 keeps pointers into it
  for (const TrainOption& row : table) {
    if (row.flag.empty()) continue;
    args->flags.emplace_back();
    AddTableFlag(cmd, row, &args->flags.back());
    if (row.key == "data") AddRunFlags(cmd, args.get());  // --help: the scene, then the run
  }
  args->hexplane = AddHexPlaneTrainFlags(cmd);
  args->cmd = cmd;
  cmd->callback([args] { RunTrain(*args); });
}

}  // namespace hdr4d::cli
