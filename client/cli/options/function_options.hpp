// Options shared by the commands that work on a robot and a function spec (compute,
// generate, check): the same flags, the same help text, the same loading and errors.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "robodiff/functions/function_spec.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::cli {

struct RobotArgs {
  std::string urdf;
  bool floating_base = false;
};

// --urdf FILE (required) and --floating-base.
void addRobotOptions(CLI::App& cmd, RobotArgs& args);

// The URDF as a model, with a free-flyer root joint if --floating-base was given.
Model loadRobot(const RobotArgs& args);

// --spec FILE; `required` for generate and check, an alternative to --function in compute.
CLI::Option* addSpecOption(CLI::App& cmd, std::string& path, bool required);

}  // namespace robodiff::cli
