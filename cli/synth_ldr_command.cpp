#include "cli/commands.h"

namespace hdr4d::cli {

void AddSynthLdrCommand(CLI::App& app) {}

}  // namespace hdr4d::cli
