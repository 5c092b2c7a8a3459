// The `hdr4d` command line: every subcommand registered on one CLI::App, and the one place that
// turns any failure into the README's promise: one line "hdr4d: error: <file>: <problem>" on
// stderr, hdr4d's line last, exit code 1 (bad flags included); --help and --version exit 0.
#pragma once

#include <CLI/CLI.hpp>

#include <memory>

namespace hdr4d::cli {

// The root app with every subcommand (cli/app_test.cpp inspects its flags).
std::unique_ptr<CLI::App> MakeApp();

// Parses and runs; returns the process exit code.
int RunApp(CLI::App& app, int argc, char** argv);

}  // namespace hdr4d::cli
