// robodiff: command-line entry point.
#include <exception>
#include <iostream>

#include "commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"robodiff: rigid-body dynamics and their derivatives, as a service"};
  app.require_subcommand(1);
  robodiff::cli::addComputeCommand(app);
  robodiff::cli::addMakeRobotCommand(app);
  robodiff::cli::addGenerateCommand(app);
  robodiff::cli::addCheckCommand(app);
  robodiff::cli::addBenchCommand(app);
  robodiff::cli::addWarmupCommand(app);
  robodiff::cli::addCacheCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "robodiff: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
