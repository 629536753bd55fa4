// Physically invalid models are refused at load with the link named (a negative mass,
// an inertia that is not positive semi-definite or violates the triangle inequality,
// non-finite numbers, a moving body that leaves the mass matrix singular), while every
// real and generated robot, massless virtual links included, still loads.
#include <gtest/gtest.h>

#include <filesystem>
#include <initializer_list>
#include <string>

#include "robodiff/model/robot_generator.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

std::string inertial(const std::string& mass, const std::string& moments = "0.1 0.1 0.1",
                     const std::string& origin = "0 0 0.1") {
  std::string ixx = moments.substr(0, moments.find(' '));
  std::string rest = moments.substr(moments.find(' ') + 1);
  std::string iyy = rest.substr(0, rest.find(' '));
  std::string izz = rest.substr(rest.find(' ') + 1);
  return "<inertial><origin xyz=\"" + origin + "\"/><mass value=\"" + mass + "\"/><inertia ixx=\"" + ixx +
         "\" ixy=\"0\" ixz=\"0\" iyy=\"" + iyy + "\" iyz=\"0\" izz=\"" + izz + "\"/></inertial>";
}

std::string revolute(const std::string& name, const std::string& parent, const std::string& child,
                     const std::string& xyz = "0 0 0.2") {
  return "<joint name=\"" + name + "\" type=\"revolute\"><parent link=\"" + parent + "\"/><child link=\"" + child +
         "\"/><origin xyz=\"" + xyz + "\"/><axis xyz=\"0 0 1\"/>"
         "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>";
}

std::string fixed(const std::string& name, const std::string& parent, const std::string& child) {
  return "<joint name=\"" + name + "\" type=\"fixed\"><parent link=\"" + parent + "\"/><child link=\"" + child +
         "\"/><origin xyz=\"0 0 0.1\"/></joint>";
}

// base -(shoulder)- upper -(elbow)- lower -(fixed)- tool, with the given <inertial>s.
std::string arm(const std::string& upper, const std::string& lower, const std::string& tool = "") {
  return "<robot name=\"arm\"><link name=\"base\">" + inertial("3") + "</link>" + revolute("shoulder", "base", "upper") +
         "<link name=\"upper\">" + upper + "</link>" + revolute("elbow", "upper", "lower", "0.3 0 0") +
         "<link name=\"lower\">" + lower + "</link>" + fixed("tool_joint", "lower", "tool") + "<link name=\"tool\">" +
         tool + "</link></robot>";
}

template <class Error>
std::string errorOf(const std::string& xml, RootJoint root = RootJoint::Fixed) {
  try {
    loadUrdfString(xml, root, "bad.urdf", {}, PhysicsCheck::Dynamic);
  } catch (const Error& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected another exception type, got: " << e.what();
    return "";
  }
  ADD_FAILURE() << "the URDF loaded:\n" << xml;
  return "";
}

::testing::AssertionResult mentions(const std::string& message, std::initializer_list<std::string> parts) {
  for (const std::string& part : parts)
    if (message.find(part) == std::string::npos)
      return ::testing::AssertionFailure() << "message \"" << message << "\" does not contain \"" << part << "\"";
  return ::testing::AssertionSuccess();
}

TEST(PhysicalValidity, TheBaselineArmLoadsWithAMasslessTool) {
  Model m = loadUrdfString(arm(inertial("1"), inertial("1")), RootJoint::Fixed, "arm.urdf", {}, PhysicsCheck::Dynamic);
  EXPECT_EQ(m.njoints(), 2);
  Model floating = loadUrdfString(arm(inertial("1"), inertial("1")), RootJoint::FreeFlyer, "arm.urdf", {},
                                  PhysicsCheck::Dynamic);
  EXPECT_EQ(floating.njoints(), 3);
}

TEST(PhysicalValidity, ZeroMassesAreRefusedNamingTheLink) {
  const std::string zero = inertial("0", "0 0 0");
  std::string msg = errorOf<PhysicallyInvalidModel>(arm(zero, zero));
  EXPECT_TRUE(mentions(msg, {"bad.urdf", "joint 'elbow'", "links 'lower', 'tool'", "mass matrix is singular"}));
  // No <inertial> at all: the same.
  EXPECT_TRUE(mentions(errorOf<PhysicallyInvalidModel>(arm("", "")), {"joint 'elbow'", "singular"}));
  // Floating base and everything massless.
  EXPECT_TRUE(mentions(errorOf<PhysicallyInvalidModel>(arm(zero, zero), RootJoint::FreeFlyer),
                       {"joint 'elbow'", "singular"}));
}

TEST(PhysicalValidity, ARevoluteJointWhoseSubtreeIsMasslessIsRefused) {
  // The upper arm is heavy, but nothing beyond the elbow has mass or inertia.
  std::string msg = errorOf<PhysicallyInvalidModel>(arm(inertial("2"), "", inertial("0", "0 0 0")));
  EXPECT_TRUE(mentions(msg, {"joint 'elbow'", "links 'lower', 'tool'", "singular"}));
}

TEST(PhysicalValidity, APointMassOnTheAxisIsRefused) {
  // Mass but no inertia, on the elbow's axis: the elbow moves nothing.
  std::string msg = errorOf<PhysicallyInvalidModel>(arm(inertial("2"), inertial("1", "0 0 0", "0 0 0.5")));
  EXPECT_TRUE(mentions(msg, {"joint 'elbow'", "links 'lower', 'tool'", "singular"}));
}

TEST(PhysicalValidity, AMasslessLinkBesideHeavyOnesLoads) {
  // Only the upper arm is massless: the elbow's body carries the inertia for both joints.
  Model m = loadUrdfString(arm("", inertial("1")), RootJoint::Fixed, "arm.urdf", {}, PhysicsCheck::Dynamic);
  EXPECT_EQ(m.njoints(), 2);
}

TEST(PhysicalValidity, NegativeMassIsRefused) {
  std::string msg = errorOf<PhysicallyInvalidModel>(arm(inertial("-1"), inertial("1")));
  EXPECT_TRUE(mentions(msg, {"bad.urdf:1", "link 'upper'", "negative mass -1"}));
}

TEST(PhysicalValidity, InertiaViolatingTheTriangleInequalityIsRefused) {
  std::string msg = errorOf<PhysicallyInvalidModel>(arm(inertial("1", "1 1 3"), inertial("1")));
  EXPECT_TRUE(mentions(msg, {"link 'upper'", "inertia violates the triangle inequality", "principal moments 1, 1, 3"}));
  // A thin rod (equality, rounded) is a body.
  EXPECT_NO_THROW(loadUrdfString(arm(inertial("1", "0.0833 0.0833 0.16665"), inertial("1")), RootJoint::Fixed,
                                 "rod.urdf", {}, PhysicsCheck::Dynamic));
}

TEST(PhysicalValidity, InertiaNotPositiveSemiDefiniteIsRefused) {
  std::string msg = errorOf<PhysicallyInvalidModel>(arm(inertial("1", "0.1 -0.1 0.1"), inertial("1")));
  EXPECT_TRUE(mentions(msg, {"link 'upper'", "not positive semi-definite"}));
}

// Kinematic checks (the default: URDFs whose inertias are to be identified) accept what
// only dynamics needs, and still refuse what no body has.
TEST(PhysicalValidity, KinematicChecksAcceptMasslessRobots) {
  const std::string zero = inertial("0", "0 0 0");
  EXPECT_EQ(loadUrdfString(arm(zero, zero)).njoints(), 2);
  EXPECT_EQ(loadUrdfString(arm(inertial("1", "1 1 3"), inertial("1"))).njoints(), 2);
  EXPECT_THROW(loadUrdfString(arm(inertial("-1"), inertial("1"))), PhysicallyInvalidModel);
}

TEST(PhysicalValidity, NonFiniteNumbersAreRefused) {
  std::string origin = errorOf<ModelError>(arm(inertial("1", "0.1 0.1 0.1", "nan 0 0"), inertial("1")));
  EXPECT_TRUE(mentions(origin, {"link 'upper'", "'nan' is not a finite number"}));
  std::string mass = errorOf<ModelError>(arm(inertial("1"), inertial("inf")));
  EXPECT_TRUE(mentions(mass, {"link 'lower'", "'inf' is not a finite number"}));
  std::string joint = errorOf<ModelError>(
      arm(inertial("1"), inertial("1")).replace(arm(inertial("1"), inertial("1")).find("0.3 0 0"), 7, "0.3 NaN 0"));
  EXPECT_TRUE(mentions(joint, {"joint 'elbow'", "'NaN' is not a finite number"}));
}

// Every URDF of ../shared and examples/, and generated robots of every shape, load with
// a fixed and a floating base.
void expectLoads(const std::string& xml, const std::string& label) {
  for (RootJoint root : {RootJoint::Fixed, RootJoint::FreeFlyer}) {
    try {
      loadUrdfString(xml, root, label, {}, PhysicsCheck::Dynamic);
    } catch (const std::exception& e) {
      ADD_FAILURE() << label << (root == RootJoint::Fixed ? " (fixed base)" : " (floating base)") << ": " << e.what();
    }
  }
}

TEST(PhysicalValidity, EveryExampleAndGeneratedRobotLoads) {
  int examples = 0;
  for (const auto& entry : std::filesystem::directory_iterator(testing::sourceDir() / "examples" / "robots"))
    if (entry.path().extension() == ".urdf") {
      expectLoads(testing::readFile(entry.path()), entry.path().string());
      ++examples;
    }
  EXPECT_GE(examples, 3);
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    GeneratorOptions chain;
    chain.joints = 1 + static_cast<int>(seed * 3);
    chain.seed = seed;
    chain.prismatic_fraction = 0.3;
    chain.continuous_fraction = 0.2;
    expectLoads(generateRobotUrdf(chain), "chain seed " + std::to_string(seed));
    GeneratorOptions tree;
    tree.kind = RobotKind::Tree;
    tree.tree = seed % 2 ? "humanoid" : "2x3,3(2x2)";
    tree.seed = seed;
    expectLoads(generateRobotUrdf(tree), "tree seed " + std::to_string(seed));
  }
}

TEST(PhysicalValidity, EverySharedRobotLoads) {
  ROBODIFF_REQUIRE_SHARED(shared);
  int robots = 0;
  for (const auto& entry : std::filesystem::directory_iterator(shared / "robots"))
    if (entry.path().extension() == ".urdf") {
      expectLoads(testing::readFile(entry.path()), entry.path().string());
      ++robots;
    }
  EXPECT_GE(robots, 3);
}

}  // namespace
}  // namespace robodiff
