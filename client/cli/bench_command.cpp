// `robodiff bench` (being written).
#include "commands.hpp"

namespace robodiff::cli {

void addBenchCommand(CLI::App& app) {
  app.add_subcommand("bench", "Benchmark generated functions for one robot")->callback([] { throw std::runtime_error("not implemented yet"); });
}

}  // namespace robodiff::cli
