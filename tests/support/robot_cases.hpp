// A generated test robot with its root option: the parameter of tests that run on the
// project's own robots (no ../shared needed).
#pragma once

#include <ostream>
#include <string>

#include "robodiff/model/robot_generator.hpp"
#include "robodiff/model/urdf_loader.hpp"

namespace robodiff::testing {

struct RobotCase {
  std::string label;
  GeneratorOptions options;
  RootJoint root = RootJoint::Fixed;

  Model load() const { return loadUrdfString(generateRobotUrdf(options), root, label); }
  friend void PrintTo(const RobotCase& c, std::ostream* os) { *os << c.label; }
};

}  // namespace robodiff::testing
