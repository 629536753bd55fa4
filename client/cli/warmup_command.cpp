// `robodiff warmup` (placeholder until implemented).
#include "commands.hpp"
namespace robodiff::cli {
void addWarmupCommand(CLI::App& app) { app.add_subcommand("warmup", "Build (robot, spec) pairs into the cache"); }
}  // namespace robodiff::cli
