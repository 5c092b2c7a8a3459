// `hdr4d train --method hexplane|hexplane-hdr|hdr-hexplane`: the grid family's own flags and its
// branch of the train command (baselines/hexplane/hexplane_train.h does the work).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "baselines/hexplane/hexplane_train.h"

namespace hdr4d::cli {

// Every --method name `hdr4d train` accepts: the Gaussian family's, then the grid family's.
std::vector<std::string> TrainMethodNames();

// Adds the grid family's flags to the train command; the options they fill.
std::shared_ptr<baselines::hexplane::HexPlaneTrainOptions> AddHexPlaneTrainFlags(CLI::App* cmd);

// Trains a grid-family run when `method` is one of them (true), with the train command's shared
// flags read from `cmd`; false for any other method. --resume without --method resumes a grid
// run as its own method.
bool TrainHexPlaneIfAsked(CLI::App* cmd, std::string method,
                          baselines::hexplane::HexPlaneTrainOptions options);

}  // namespace hdr4d::cli
