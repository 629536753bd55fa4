// A generated test robot with its root option: the parameter of tests that run on the
// project's own robots (no ../shared needed).
#pragma once

#include <ostream>
#include <string>
#include <vector>

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

// For derivative tests: a free-flying quadruped with a quarter of its joints prismatic,
// the same legs on a trunk fixed to the world (four separate chains), and a chain of 8
// joints, 40% prismatic.
inline std::vector<RobotCase> branchedAndPrismaticRobots() {
  GeneratorOptions quadruped;
  quadruped.kind = RobotKind::Tree;
  quadruped.tree = "quadruped";
  quadruped.seed = 9;
  quadruped.prismatic_fraction = 0.25;
  GeneratorOptions chain;
  chain.joints = 8;
  chain.seed = 21;
  chain.prismatic_fraction = 0.4;
  return {{"quadruped_free_flyer", quadruped, RootJoint::FreeFlyer},
          {"quadruped_fixed", quadruped, RootJoint::Fixed},
          {"chain8_prismatic", chain, RootJoint::Fixed}};
}

}  // namespace robodiff::testing
