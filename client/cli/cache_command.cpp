// `robodiff cache` (placeholder until implemented).
#include "commands.hpp"
namespace robodiff::cli {
void addCacheCommand(CLI::App& app) { app.add_subcommand("cache", "List, check and trim the cache"); }
}  // namespace robodiff::cli
