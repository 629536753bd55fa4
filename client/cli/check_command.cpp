// `robodiff check` (being written).
#include "commands.hpp"

namespace robodiff::cli {

void addCheckCommand(CLI::App& app) {
  app.add_subcommand("check", "Cross-check a generated function against the double reference and finite differences")->callback([] { throw std::runtime_error("not implemented yet"); });
}

}  // namespace robodiff::cli
