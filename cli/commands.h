// Each subcommand of `hdr4d` lives in its own file and only parses options, then calls a
// library function. Add<Name>Command registers it on the root app.
#pragma once

#include <CLI/CLI.hpp>

namespace hdr4d::cli {

void AddDatasetCommand(CLI::App& app);        // dataset check
void AddEvalCommand(CLI::App& app);           // eval PRED GT
void AddSynthLdrCommand(CLI::App& app);       // synth-ldr
void AddDemoSceneCommand(CLI::App& app);      // make-demo-scene
void AddMergeHdrCommand(CLI::App& app);       // merge-hdr
void AddTrainCommand(CLI::App& app);          // train
void AddRenderCommand(CLI::App& app);         // render
void AddGaussianSceneCommand(CLI::App& app);  // make-gaussian-scene
void AddExportPlyCommand(CLI::App& app);      // export-ply
void AddViewCommand(CLI::App& app);           // view RUN
void AddToneCurvesCommand(CLI::App& app);     // tone-curves
void AddDatagenCommand(CLI::App& app);        // datagen
void AddBenchCommand(CLI::App& app);          // bench run|table|pareto|report|stress|submit|...
void AddCalibrateCommand(CLI::App& app);      // calibrate

}  // namespace hdr4d::cli
