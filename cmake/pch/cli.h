// The command-line library's precompiled header: the libraries' list plus CLI11, which every
// subcommand file includes and which alone takes seconds to parse.
#pragma once

#include <CLI/CLI.hpp>

#include "library.h"
