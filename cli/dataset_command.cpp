#include "cli/commands.h"

namespace hdr4d::cli {

void AddDatasetCommand(CLI::App& app) {}

}  // namespace hdr4d::cli
