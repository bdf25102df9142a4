// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

// Subcommands register themselves: each cmd_<name>.cpp defines its `add` function and a
// `CommandRegistrar` at namespace scope. main.cpp adds them in `order` (the order of
// `pliant --help`).

#include "cli_common.h"

#include <vector>

namespace pliant::cli
{

struct CommandSpec
{
    const char* name;
    int order;  ///< position in `pliant --help`: 10 info, 20 remesh, 30 refine, 40 simulate, ...
    void (*add)(CLI::App& app, const GlobalOptions& global);
};

/// All registered subcommands (filled before main runs).
std::vector<CommandSpec>& command_registry();

/// Registers a subcommand at static-initialisation time.
struct CommandRegistrar
{
    explicit CommandRegistrar(CommandSpec spec) { command_registry().push_back(spec); }
};

}  // namespace pliant::cli
