#include "options/function_options.hpp"

#include "robodiff/model/urdf_loader.hpp"

namespace robodiff::cli {

void addRobotOptions(CLI::App& cmd, RobotArgs& args) {
  cmd.add_option("--urdf", args.urdf, "Robot description (URDF file)")->required()->type_name("FILE");
  cmd.add_flag("--floating-base", args.floating_base,
               "Add a free-flyer root joint (q = [x y z qx qy qz qw ...], v = [linear angular ...])");
}

Model loadRobot(const RobotArgs& args) {
  return loadUrdfFile(args.urdf, args.floating_base ? RootJoint::FreeFlyer : RootJoint::Fixed);
}

CLI::Option* addSpecOption(CLI::App& cmd, std::string& path, bool required) {
  CLI::Option* option = cmd.add_option("--spec", path,
                                       "Function spec (JSON, schema/function-spec.schema.json; examples in "
                                       "examples/specs/): the function, its variable and fixed inputs, its outputs "
                                       "(value, Jacobians, weighted Hessians) and build options; or a user function "
                                       "(inputs, define, outputs: docs/function-language.md)")
                            ->type_name("SPEC.json");
  if (required) option->required();
  return option;
}

}  // namespace robodiff::cli
