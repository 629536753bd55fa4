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
// `cache export` and `cache import` (cache_transfer_command.cpp), added by addCacheCommand.
void addCacheTransferCommands(CLI::App& cache_command);
void addKeygenCommand(CLI::App& app);    // keygen_command.cpp (keys that sign cache artifacts)
void addSecurityCommand(CLI::App& app);  // security_command.cpp (DDS Security keystore)
// Batch work (batch/): trajectories, identification, trajectory optimisation.
void addTrajectoryCommand(CLI::App& app);  // trajectory_command.cpp
void addIdentifyCommand(CLI::App& app);    // identify_command.cpp
void addTrajoptCommand(CLI::App& app);     // trajopt_command.cpp

// Clients of the running server, robodiffd (service_connection.hpp: --server, --timeout,
// exit statuses 0 OK, 1 the server answered an error, 2 bad usage, 3 no server).
void addLoadCommand(CLI::App& app);       // load_command.cpp
void addEvalCommand(CLI::App& app);       // eval_command.cpp
void addFunctionsCommand(CLI::App& app);  // functions_command.cpp
void addHealthCommand(CLI::App& app);     // health_command.cpp
void addJobCommand(CLI::App& app);        // job_command.cpp
// The subcommand names whose usage errors exit with status 2 (the service commands, and
// warmup with --server).
bool isServiceCommandLine(int argc, char** argv);

}  // namespace robodiff::cli
