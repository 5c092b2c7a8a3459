// The command line as built in-process: every flag that takes a value is validated up front.
#include "cli/app.h"

#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include "method/train/train_options_table.h"

namespace hdr4d::cli {
namespace {

// Each option of each (sub)command that takes a value, as "command --flag".
void ForEachValueOption(CLI::App* app,
                        const std::string& path,
                        const std::function<void(CLI::Option*, const std::string&)>& fn) {
  for (CLI::Option* option : app->get_options([](CLI::Option*) { return true; })) {
    if (option->get_expected_max() == 0) continue;  // a flag without a value
    fn(option, path + " " + option->get_name());
  }
  for (CLI::App* sub : app->get_subcommands([](CLI::App*) { return true; }))
    ForEachValueOption(sub, path + " " + sub->get_name(), fn);
}

// A new flag added with add_option and no check would accept anything its type converts from
// (-1 as a seed wraps to 2^64 - 1): this makes that a failing test instead.
TEST(App, EveryValueFlagHasAValidator) {
  const auto app = MakeApp();
  std::vector<std::string> unchecked;
  int checked = 0;
  ForEachValueOption(app.get(), "hdr4d", [&](CLI::Option* option, const std::string& name) {
    try {
      option->get_validator(0);
      ++checked;
    } catch (const CLI::OptionNotFound&) {
      unchecked.push_back(name);
    }
  });
  std::string list;
  for (const std::string& name : unchecked) list += "\n  " + name;
  EXPECT_TRUE(unchecked.empty()) << "value flags without a validator (cli/flags.h):" << list;
  EXPECT_GT(checked, 60);  // the walk reached every subcommand
}

TEST(App, BadValuesAreRefusedWhileParsingNamingTheFlag) {
  struct Case {
    std::vector<std::string> args;
    std::string flag;
  };
  const std::vector<Case> cases = {
      {{"train", "--data", "d", "--out", "o", "--seed", "-1"}, "--seed"},
      {{"train", "--data", "d", "--out", "o", "--seed", "18446744073709551616"}, "--seed"},
      {{"train", "--data", "d", "--out", "o", "--context-window", "0"}, "--context-window"},
      {{"train", "--data", "d", "--out", "o", "--context-size", "-1"}, "--context-size"},
      {{"train", "--data", "d", "--out", "o", "--iterations", "abc"}, "--iterations"},
      {{"train", "--data", "d", "--out", "o", "--iterations", "0"}, "--iterations"},
      {{"train", "--data", "d", "--out", "o", "--iterations", "automatic"}, "--iterations"},
      {{"train", "--data", "d", "--out", "o", "--stop-tolerance", "1.5"}, "--stop-tolerance"},
      {{"train", "--data", "d", "--out", "o", "--stop-window", "-1"}, "--stop-window"},
      {{"train", "--data", "d", "--out", "o", "--random-points", "0"}, "--random-points"},
      {{"train", "--data", "d", "--out", "o", "--background", "nan"}, "--background"},
      {{"render", "--run", "r", "--video", "0"}, "--video"},
      {{"render", "--run", "r", "--threads", "-2"}, "--threads"},
      {{"render", "--run", "r", "--video", "3", "--fps", "0"}, "--fps"},
      {{"render", "--run", "r", "--png-compression", "10"}, "--png-compression"},
      {{"tone-curves", "--run", "r", "--times", "a,b"}, "--times"},
      {{"synth-ldr", "--data", "d", "--bits", "12"}, "--bits"},
  };
  for (const Case& c : cases) {
    const auto app = MakeApp();
    std::vector<std::string> reversed(c.args.rbegin(), c.args.rend());  // CLI11 parses from the back
    try {
      app->parse(reversed);
      ADD_FAILURE() << c.args[0] << " " << c.flag << ": accepted";
    } catch (const CLI::ValidationError& e) {
      EXPECT_NE(std::string(e.what()).find(c.flag), std::string::npos) << e.what();
    } catch (const std::exception& e) {
      ADD_FAILURE() << c.flag << ": " << e.what();
    }
  }
}

// `hdr4d train`'s options are the option table's rows: each flag with its help, and a range
// stated in the words its errors use.
TEST(App, TrainFlagsAreTheOptionTablesRows) {
  const auto app = MakeApp();
  CLI::App* train = app->get_subcommand("train");
  std::size_t rows = 0;
  for (const method::TrainOption& row : method::TrainOptionTable()) {
    if (row.flag.empty()) continue;
    ++rows;
    const CLI::Option* option = train->get_option(row.flag);
    EXPECT_EQ(option->get_description(), row.help) << row.flag;
    if (row.type == method::OptionType::kInt || row.type == method::OptionType::kDouble ||
        row.type == method::OptionType::kFloat || row.type == method::OptionType::kInt64) {
      EXPECT_NE(option->get_type_name().find(row.range.Bounds()), std::string::npos)
          << row.flag << ": " << option->get_type_name();
    }
  }
  // Every row is a flag (their number is checked in train_options_table_test.cpp).
  // The six flags that are not options of the run (--overwrite among them), and the grid
  // family's four (cli/train_hexplane.h: --rays, --grid-voxels, --time-grid, --grid-background).
  EXPECT_EQ(train->get_options().size(), rows + 6u + 4u + 1u);  // + --help
}

TEST(App, ATrainFlagOutOfRangeIsRefusedInTheWordsOfItsHelp) {
  const auto app = MakeApp();
  const std::vector<std::string> args = {"2e6", "--hdr-weight", "o", "--out", "d", "--data",
                                         "train"};  // CLI11 parses from the back
  try {
    app->parse(std::vector<std::string>(args));
    ADD_FAILURE() << "accepted";
  } catch (const CLI::ValidationError& e) {
    EXPECT_NE(std::string(e.what()).find("--hdr-weight: expected a number in [0, 1e+06], got '2e6'"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace hdr4d::cli
