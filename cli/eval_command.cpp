#include "cli/commands.h"

namespace hdr4d::cli {

void AddEvalCommand(CLI::App& app) {}

}  // namespace hdr4d::cli
