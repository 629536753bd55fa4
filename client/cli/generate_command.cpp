// `robodiff generate` (being written).
#include "commands.hpp"

namespace robodiff::cli {

void addGenerateCommand(CLI::App& app) {
  app.add_subcommand("generate", "Generate, compile and describe a function library from a URDF and a spec")->callback([] { throw std::runtime_error("not implemented yet"); });
}

}  // namespace robodiff::cli
