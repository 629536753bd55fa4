// robodiff: command-line entry point.
#include <cstring>
#include <exception>
#include <iostream>
#include <string>

#include "commands/commands.hpp"
#include "service/service_connection.hpp"

namespace robodiff::cli {

bool isServiceCommandLine(int argc, char** argv) {
  if (argc < 2) return false;
  const std::string command = argv[1];
  if (command == "load" || command == "eval" || command == "functions" || command == "health" || command == "job")
    return true;
  if (command != "warmup") return false;
  for (int i = 2; i < argc; ++i)
    if (std::strcmp(argv[i], "--server") == 0 || std::strncmp(argv[i], "--server=", 9) == 0) return true;
  return false;
}

}  // namespace robodiff::cli

int main(int argc, char** argv) {
  using namespace robodiff::cli;
  CLI::App app{"robodiff: rigid-body dynamics and their derivatives, as a service"};
  app.require_subcommand(1);
  addComputeCommand(app);
  addMakeRobotCommand(app);
  addGenerateCommand(app);
  addCheckCommand(app);
  addBenchCommand(app);
  addWarmupCommand(app);
  addCacheCommand(app);
  addKeygenCommand(app);
  addSecurityCommand(app);
  addTrajectoryCommand(app);
  addIdentifyCommand(app);
  addTrajoptCommand(app);
  addLoadCommand(app);
  addEvalCommand(app);
  addFunctionsCommand(app);
  addHealthCommand(app);
  addJobCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::RuntimeError& e) {
    return e.get_exit_code();  // a command's own status (e.g. warmup: 1 when a build failed)
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    // The service commands document 2 for bad usage (CLI11's own codes are 100 and up).
    return code != 0 && isServiceCommandLine(argc, argv) ? kExitUsage : code;
  } catch (const UsageError& e) {
    std::cerr << "robodiff: usage: " << e.what() << "\n";
    return kExitUsage;
  } catch (const ServiceError& e) {
    std::cerr << "robodiff: " << e.what() << "\n";
    return e.exitCode();
  } catch (const std::exception& e) {
    std::cerr << "robodiff: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
