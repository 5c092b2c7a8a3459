// The camera-pipeline flags shared by `synth-ldr --data` and `datagen`
// (core/radiometry/camera_pipeline.h): --pipeline NAME and each model's parameters.
#pragma once

#include <CLI/CLI.hpp>

#include <memory>
#include <vector>

#include "core/radiometry/camera_pipeline.h"

namespace hdr4d::cli {

class PipelineFlags {
 public:
  // Adds the flags to `cmd`; they write into `options`, which must outlive the parse.
  PipelineFlags(CLI::App* cmd, CameraPipelineOptions& options);
  // After the parse: refuses a parameter given for a pipeline that does not use it (a
  // --wb-drift with --pipeline fixed would otherwise be silently ignored).
  void Check() const;

 private:
  struct Parameter {
    CLI::Option* option;
    std::vector<std::string> pipelines;  // empty: any pipeline
  };
  CameraPipelineOptions& options_;
  std::vector<Parameter> parameters_;
};

}  // namespace hdr4d::cli
