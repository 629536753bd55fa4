// The robot generator: its URDFs load with both root joints, have the requested shape,
// valid inertias, varied axes and origins, merged fixed links, and are the same bytes
// for the same options (the committed example robots included).
#include "robodiff/model/robot_generator.hpp"

#include <algorithm>
#include <map>
#include <regex>
#include <set>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "robodiff/model/canonical.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

GeneratorOptions chain(int joints, std::uint64_t seed = 0) {
  GeneratorOptions o;
  o.kind = RobotKind::Chain;
  o.joints = joints;
  o.seed = seed;
  return o;
}

GeneratorOptions tree(const std::string& spec, std::uint64_t seed = 0) {
  GeneratorOptions o;
  o.kind = RobotKind::Tree;
  o.tree = spec;
  o.seed = seed;
  return o;
}

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// Sum of every <mass value="..."/> in the text.
double totalMass(const std::string& urdf) {
  static const std::regex mass("<mass value=\"([^\"]+)\"");
  double sum = 0;
  for (auto it = std::sregex_iterator(urdf.begin(), urdf.end(), mass); it != std::sregex_iterator(); ++it)
    sum += std::stod((*it)[1]);
  return sum;
}

// ---------------------------------------------------------------------------------
// Tree specs

TEST(RobotGeneratorSpec, NamesBranchesInSpecOrder) {
  auto b = parseTreeSpec("2x6,2x7");
  ASSERT_EQ(b.size(), 4u);
  EXPECT_EQ(b[0].name, "branch0");
  EXPECT_EQ(b[1].name, "branch1");
  EXPECT_EQ(b[2].name, "branch2");
  EXPECT_EQ(b[3].name, "branch3");
  EXPECT_EQ(b[1].length, 6);
  EXPECT_EQ(b[2].length, 7);
  EXPECT_EQ(countJoints(b), 26);
}

TEST(RobotGeneratorSpec, ZeroPadsTenOrMoreSiblings) {
  auto b = parseTreeSpec("12x1");
  ASSERT_EQ(b.size(), 12u);
  EXPECT_EQ(b.front().name, "branch00");
  EXPECT_EQ(b.back().name, "branch11");
  // The padding keeps urdfdom's order (children sorted by joint name) the spec's order.
  Model m = loadUrdfString(generateRobotUrdf(tree("12x1")));
  ASSERT_EQ(m.njoints(), 12);
  EXPECT_EQ(m.joints[2].name, "branch02_joint1");
  EXPECT_EQ(m.joints[10].name, "branch10_joint1");
}

TEST(RobotGeneratorSpec, NestedAndLabelledBranches) {
  auto b = parseTreeSpec(" 3 ( 2x4 ), arm:2x5(1)");
  ASSERT_EQ(b.size(), 3u);
  EXPECT_EQ(b[0].name, "branch0");
  EXPECT_EQ(b[0].length, 3);
  ASSERT_EQ(b[0].children.size(), 2u);
  EXPECT_EQ(b[0].children[0].name, "branch0_0");
  EXPECT_EQ(b[0].children[1].name, "branch0_1");
  EXPECT_EQ(b[0].children[1].length, 4);
  EXPECT_EQ(b[1].name, "arm0");
  EXPECT_EQ(b[2].name, "arm1");
  ASSERT_EQ(b[2].children.size(), 1u);
  EXPECT_EQ(b[2].children[0].name, "arm1_0");
  EXPECT_EQ(countJoints(b), 3 + 8 + 2 * (5 + 1));
}

TEST(RobotGeneratorSpec, Presets) {
  auto q = parseTreeSpec("quadruped");
  ASSERT_EQ(q.size(), 4u);
  for (const auto& leg : q) EXPECT_EQ(leg.length, 3);
  EXPECT_EQ(q[0].name, "front_left_leg");

  auto h = parseTreeSpec("humanoid");
  EXPECT_EQ(countJoints(h), 30);
  ASSERT_EQ(h.size(), 3u);
  EXPECT_EQ(h[2].name, "torso");
  ASSERT_EQ(h[2].children.size(), 3u);
  EXPECT_EQ(h[2].children[0].name, "left_arm");
  EXPECT_EQ(h[2].children[0].length, 7);
  EXPECT_EQ(h[2].children[2].name, "head");
}

TEST(RobotGeneratorSpec, RejectsBadSpecs) {
  for (const char* bad : {"", "x", "2x", "0", "2x0", "a:", "leg", "3(2", "3)", "2,,2", "3(2x2))", "1-2",
                          "99999", "leg:2x2,leg:2x1", "a:1,a:1", "2x3;"}) {
    EXPECT_THROW(parseTreeSpec(bad), std::invalid_argument) << "spec \"" << bad << "\"";
  }
  try {
    parseTreeSpec("2x");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("\"2x\""), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("position 3"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------
// Generated robots

TEST(RobotGenerator, ChainsLoadWithBothRootJoints) {
  for (int n : {1, 6, 30, 60}) {
    const std::string urdf = generateRobotUrdf(chain(n, 3));
    Model fixed = loadUrdfString(urdf, RootJoint::Fixed);
    EXPECT_EQ(fixed.njoints(), n);
    EXPECT_EQ(fixed.nq, n);
    EXPECT_EQ(fixed.nv, n);
    EXPECT_EQ(fixed.name, "chain" + std::to_string(n));
    for (int j = 0; j < n; ++j) {
      EXPECT_EQ(fixed.joints[j].parent, j - 1);
      EXPECT_EQ(fixed.joints[j].name, "joint" + std::to_string(j + 1));
    }
    Model floating = loadUrdfString(urdf, RootJoint::FreeFlyer);
    EXPECT_EQ(floating.njoints(), n + 1);
    EXPECT_EQ(floating.nq, n + 7);
    EXPECT_EQ(floating.nv, n + 6);
    EXPECT_EQ(floating.joints[1].parent, 0);
  }
}

TEST(RobotGenerator, TreesHaveTheSpecifiedBranches) {
  for (const std::string spec : {"4x6", "2x6,2x7", "3(2x4),arm:2x5(1)", "12x1", "quadruped", "humanoid"}) {
    SCOPED_TRACE(spec);
    const auto branches = parseTreeSpec(spec);
    const std::string urdf = generateRobotUrdf(tree(spec, 11));
    for (RootJoint root : {RootJoint::Fixed, RootJoint::FreeFlyer}) {
      Model m = loadUrdfString(urdf, root);
      const int offset = root == RootJoint::FreeFlyer ? 1 : 0;
      ASSERT_EQ(m.njoints(), countJoints(branches) + offset);
      EXPECT_EQ(m.nv, countJoints(branches) + 6 * offset);
      // Joint k of a branch hangs from joint k-1; joint 1 from the parent branch's
      // last joint, or from the root.
      auto check = [&](auto&& self, const std::vector<TreeBranch>& list, int parent) -> void {
        for (const TreeBranch& b : list) {
          int above = parent;
          for (int k = 1; k <= b.length; ++k) {
            int j = m.jointIndex(b.name + "_joint" + std::to_string(k));
            EXPECT_EQ(m.joints[j].parent, above) << m.joints[j].name;
            above = j;
          }
          EXPECT_EQ(m.subtree_end[above] - above, 1 + countJoints(b.children)) << b.name;
          self(self, b.children, above);
        }
      };
      check(check, branches, offset - 1);
    }
  }
}

TEST(RobotGenerator, HumanoidArmsHangFromTheTorso) {
  Model m = loadUrdfString(generateRobotUrdf(tree("humanoid")), RootJoint::FreeFlyer);
  EXPECT_EQ(m.name, "humanoid");
  EXPECT_EQ(m.nv, 36);
  const int torso = m.jointIndex("torso_joint2");
  for (const char* first : {"left_arm_joint1", "right_arm_joint1", "head_joint1"})
    EXPECT_EQ(m.joints[m.jointIndex(first)].parent, torso) << first;
  EXPECT_EQ(m.joints[m.jointIndex("left_leg_joint1")].parent, 0);
  EXPECT_EQ(m.joints[m.jointIndex("torso_joint1")].parent, 0);
}

TEST(RobotGenerator, SameSeedSameTextOtherSeedOtherText) {
  for (const GeneratorOptions& o : {chain(30, 5), tree("humanoid", 5)}) {
    const std::string a = generateRobotUrdf(o);
    EXPECT_EQ(a, generateRobotUrdf(o));
    GeneratorOptions other = o;
    other.seed = 6;
    const std::string b = generateRobotUrdf(other);
    // Same shape, other numbers (the canonical form leaves out the comment naming the seed).
    Model ma = loadUrdfString(a), mb = loadUrdfString(b);
    EXPECT_EQ(ma.njoints(), mb.njoints());
    EXPECT_NE(canonicalForm(ma), canonicalForm(mb));
    EXPECT_EQ(canonicalForm(ma), canonicalForm(loadUrdfString(generateRobotUrdf(o))));
  }
}

TEST(RobotGenerator, InertiasArePhysicallyValid) {
  for (std::uint64_t seed = 0; seed < 5; ++seed) {
    for (const GeneratorOptions& o : {chain(60, seed), tree("humanoid", seed), tree("3(2x4),2x2", seed)}) {
      const std::string urdf = generateRobotUrdf(o);
      // Every link's mass lies in the promised range.
      static const std::regex mass("<mass value=\"([^\"]+)\"");
      for (auto it = std::sregex_iterator(urdf.begin(), urdf.end(), mass); it != std::sregex_iterator(); ++it) {
        double value = std::stod((*it)[1]);
        EXPECT_GE(value, 0.2);
        EXPECT_LE(value, 5.0);
      }
      // Every composite body of the model (the base included, on a free flyer).
      Model m = loadUrdfString(urdf, RootJoint::FreeFlyer);
      for (int j = 0; j < m.njoints(); ++j) {
        const Inertia<double>& body = m.bodies[j];
        SCOPED_TRACE(m.joints[j].name);
        EXPECT_GT(body.mass, 0.0);
        EXPECT_TRUE(body.lever.allFinite());
        EXPECT_LE((body.inertia - body.inertia.transpose()).cwiseAbs().maxCoeff(), 1e-15);
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(body.inertia);
        Eigen::Vector3d p = eig.eigenvalues();  // ascending
        EXPECT_GT(p[0], 0.0);
        EXPECT_GE(p[0] + p[1], p[2] * (1 - 1e-12));
      }
    }
  }
}

TEST(RobotGenerator, FixedLinksAreMergedAndKeepTheirMass) {
  const std::string urdf = generateRobotUrdf(tree("2x6,3(2x3)", 2));
  Model m = loadUrdfString(urdf, RootJoint::FreeFlyer);
  const int moving = 2 * 6 + 3 + 2 * 3;
  ASSERT_EQ(m.njoints(), moving + 1);
  const int links = count(urdf, "<link ");
  const int fixed = count(urdf, "type=\"fixed\"");
  EXPECT_GE(fixed, 4);  // a tool on each of the four leaf branches, maybe spacers
  EXPECT_EQ(links, moving + 1 + fixed);
  EXPECT_LT(m.njoints(), links);
  // Fixed joints and their links stay as frames.
  for (const char* frame : {"branch0_tool_joint", "branch0_tool", "branch2_1_tool"})
    EXPECT_TRUE(m.findFrame(frame).has_value()) << frame;
  EXPECT_EQ(m.frames[m.frameIndex("branch0_tool_joint")].type, FrameType::FixedJoint);
  EXPECT_EQ(m.frames[m.frameIndex("branch0_tool")].parent_joint, m.jointIndex("branch0_joint6"));
  // No mass is lost in the merge.
  double model_mass = 0;
  for (const auto& body : m.bodies) model_mass += body.mass;
  EXPECT_NEAR(model_mass, totalMass(urdf), 1e-12 * model_mass);
}

TEST(RobotGenerator, SpacersAppearInLongChains) {
  const std::string urdf = generateRobotUrdf(chain(60, 1));
  EXPECT_GE(count(urdf, "_joint\" type=\"fixed\""), 3);  // spacers and the tool
  Model m = loadUrdfString(urdf);
  EXPECT_EQ(m.njoints(), 60);
}

TEST(RobotGenerator, AxesAndOriginsAreVaried) {
  Model m = loadUrdfString(generateRobotUrdf(chain(60, 4)));
  std::map<AxisKind, int> kinds;
  int negative = 0, identity = 0, quarter_turns = 0, generic = 0, no_offset = 0;
  for (const Joint& j : m.joints) {
    ++kinds[j.axis_kind];
    EXPECT_NEAR(j.axis.norm(), 1.0, 1e-15);
    if (j.axis == -Eigen::Vector3d::UnitX() || j.axis == -Eigen::Vector3d::UnitY() ||
        j.axis == -Eigen::Vector3d::UnitZ())
      ++negative;
    const Eigen::Matrix3d& r = j.placement.rotation;
    if (r.isIdentity(0)) ++identity;
    else if ((r.array() == 0 || r.array().abs() == 1).all()) ++quarter_turns;
    else ++generic;
    if (j.placement.translation.isZero(0)) ++no_offset;
  }
  EXPECT_GT(kinds[AxisKind::X], 0);
  EXPECT_GT(kinds[AxisKind::Y], 0);
  EXPECT_GT(kinds[AxisKind::Z], 0);
  EXPECT_GT(kinds[AxisKind::Unaligned] - negative, 0);
  EXPECT_GT(negative, 0);
  EXPECT_GT(identity, 0);
  EXPECT_GT(quarter_turns, 0);
  EXPECT_GT(generic, 0);
  EXPECT_LT(no_offset, 60);
}

TEST(RobotGenerator, JointTypesFollowTheFractions) {
  GeneratorOptions o = chain(40, 9);
  o.prismatic_fraction = 0.25;
  o.continuous_fraction = 0.1;
  for (RootJoint root : {RootJoint::Fixed, RootJoint::FreeFlyer}) {
    Model m = loadUrdfString(generateRobotUrdf(o), root);
    int prismatic = 0, continuous = 0;
    for (const Joint& j : m.joints) {
      if (j.type == JointType::FreeFlyer) continue;
      prismatic += j.type == JointType::Prismatic;
      continuous += j.continuous;
      EXPECT_GT(j.effort_limit[0], 0.0);
      EXPECT_GT(j.velocity_limit[0], 0.0);
      EXPECT_TRUE(std::isfinite(j.effort_limit[0]) && std::isfinite(j.velocity_limit[0]));
      if (j.continuous) {
        EXPECT_TRUE(std::isinf(j.lower[0]) && std::isinf(j.upper[0]));
      } else {
        EXPECT_TRUE(std::isfinite(j.lower[0]) && std::isfinite(j.upper[0]));
        EXPECT_LT(j.lower[0], 0.0);
        EXPECT_GT(j.upper[0], 0.0);
      }
    }
    EXPECT_EQ(prismatic, 10);
    EXPECT_EQ(continuous, 4);
  }
  // No fractions: revolute joints with limits only.
  Model plain = loadUrdfString(generateRobotUrdf(chain(40, 9)));
  for (const Joint& j : plain.joints) {
    EXPECT_EQ(j.type, JointType::Revolute);
    EXPECT_FALSE(j.continuous);
  }
}

TEST(RobotGenerator, RejectsBadOptions) {
  EXPECT_THROW(generateRobotUrdf(chain(0)), std::invalid_argument);
  EXPECT_THROW(generateRobotUrdf(chain(kMaxGeneratedJoints + 1)), std::invalid_argument);
  EXPECT_THROW(generateRobotUrdf(tree("2x")), std::invalid_argument);
  GeneratorOptions o = chain(6);
  o.prismatic_fraction = -0.1;
  EXPECT_THROW(generateRobotUrdf(o), std::invalid_argument);
  o.prismatic_fraction = 0.7;
  o.continuous_fraction = 0.5;
  EXPECT_THROW(generateRobotUrdf(o), std::invalid_argument);
  o = chain(6);
  o.name = "a robot";
  EXPECT_THROW(generateRobotUrdf(o), std::invalid_argument);
  o.name = "<robot>";
  EXPECT_THROW(generateRobotUrdf(o), std::invalid_argument);
  o.name = "arm-7.v2_x";
  EXPECT_NO_THROW(generateRobotUrdf(o));
}

// ---------------------------------------------------------------------------------
// The committed example robots: examples/robots/README.md gives the make-robot command
// of each; these are the same options through the library.

struct ExampleRobot {
  const char* file;
  GeneratorOptions options;
  int joints;  // moving joints
};

std::vector<ExampleRobot> exampleRobots() {
  GeneratorOptions arm = chain(7, 1);
  arm.name = "arm7";
  return {{"arm7.urdf", arm, 7}, {"quadruped.urdf", tree("quadruped", 1), 12}, {"humanoid.urdf", tree("humanoid", 1), 30}};
}

TEST(RobotGeneratorExamples, CommittedFilesAreReproducedByteForByte) {
  for (const ExampleRobot& robot : exampleRobots()) {
    const auto path = testing::sourceDir() / "examples" / "robots" / robot.file;
    const std::string committed = testing::readFile(path);
    EXPECT_TRUE(committed == generateRobotUrdf(robot.options))
        << path << " differs from what the generator writes now; regenerate it with the command "
        << "in examples/robots/README.md (and check why the output changed)";
  }
}

TEST(RobotGeneratorExamples, CommittedFilesLoad) {
  for (const ExampleRobot& robot : exampleRobots()) {
    const auto path = (testing::sourceDir() / "examples" / "robots" / robot.file).string();
    Model fixed = loadUrdfFile(path, RootJoint::Fixed);
    EXPECT_EQ(fixed.nv, robot.joints) << path;
    Model floating = loadUrdfFile(path, RootJoint::FreeFlyer);
    EXPECT_EQ(floating.nv, robot.joints + 6) << path;
  }
}

}  // namespace
}  // namespace robodiff
