#include "cli/commands.h"

namespace hdr4d::cli {

void AddDemoSceneCommand(CLI::App& app) {}

}  // namespace hdr4d::cli
