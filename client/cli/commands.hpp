// The subcommands of the `robodiff` tool. Each adds itself to the app; its callback
// throws on bad input (std::exception with a message naming the problem) and main
// turns that into a message on stderr and a non-zero exit status.
#pragma once

#include <CLI/CLI.hpp>

namespace robodiff::cli {

void addComputeCommand(CLI::App& app);
void addMakeRobotCommand(CLI::App& app);
void addGenerateCommand(CLI::App& app);  // generate_command.cpp
void addCheckCommand(CLI::App& app);     // check_command.cpp
void addBenchCommand(CLI::App& app);     // bench_command.cpp
void addWarmupCommand(CLI::App& app);    // warmup_command.cpp
void addCacheCommand(CLI::App& app);     // cache_command.cpp

}  // namespace robodiff::cli
