// Loading URDFs into a Model: joint order, q/v layout, frames, fixed-joint merging,
// joint kinds and limits, axis and rotation clean-up, look-ups. The robots are written
// here; urdf_pinocchio_models_test.cpp compares with Pinocchio's models of ../shared's robots.
#include "robodiff/model/urdf_loader.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace robodiff {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const double kHalfPi = std::acos(0.0);

// The children of `base` are listed c, a, b in the file and their child links are named
// in the opposite order (link_x, link_z, link_y), so only "depth-first, children sorted
// by joint name" gives a, a2, b, b_tool, c.
const std::string kTree = R"(<?xml version="1.0"?>
<robot name="tree">
  <link name="base">
    <inertial>
      <origin xyz="0.01 0.02 0.03"/>
      <mass value="3"/>
      <inertia ixx="0.3" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.1"/>
    </inertial>
  </link>
  <joint name="c_joint" type="revolute">
    <parent link="base"/>
    <child link="link_x"/>
    <origin xyz="0 0 0.3"/>
    <axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="30" velocity="3"/>
    <dynamics damping="0.5" friction="0.25"/>
  </joint>
  <link name="link_x">
    <inertial>
      <mass value="1"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/>
    </inertial>
  </link>
  <joint name="a_joint" type="continuous">
    <parent link="base"/>
    <child link="link_z"/>
    <origin xyz="0.1 0 0"/>
    <axis xyz="0 1 0"/>
  </joint>
  <link name="link_z"/>
  <joint name="a2_joint" type="prismatic">
    <parent link="link_z"/>
    <child link="a2_link"/>
    <origin xyz="0 0 0.2"/>
    <axis xyz="1 0 0"/>
    <limit lower="-0.5" upper="0.25" effort="100" velocity="0.5"/>
  </joint>
  <link name="a2_link"/>
  <joint name="b_joint" type="revolute">
    <parent link="base"/>
    <child link="link_y"/>
    <origin xyz="0 0.2 0" rpy="0 0 1.5707963267948966"/>
    <axis xyz="1 0 0"/>
    <limit lower="-1" upper="2" effort="20" velocity="4"/>
  </joint>
  <link name="link_y"/>
  <joint name="b_fixed" type="fixed">
    <parent link="link_y"/>
    <child link="b_tool"/>
    <origin xyz="0 0 0.5"/>
  </joint>
  <link name="b_tool"/>
  <joint name="b_tool_joint" type="revolute">
    <parent link="b_tool"/>
    <child link="b_tip"/>
    <origin xyz="0.05 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-0.5" upper="0.5" effort="5" velocity="6"/>
  </joint>
  <link name="b_tip"/>
</robot>
)";

struct ExpectedFrame {
  std::string name;
  FrameType type;
  int parent_joint;
};

void expectFrames(const Model& m, const std::vector<ExpectedFrame>& expected) {
  ASSERT_EQ(m.nframes(), static_cast<int>(expected.size())) << ::testing::PrintToString(m.frameNames());
  for (size_t f = 0; f < expected.size(); ++f) {
    SCOPED_TRACE("frame " + std::to_string(f) + " '" + expected[f].name + "'");
    EXPECT_EQ(m.frames[f].name, expected[f].name);
    EXPECT_EQ(m.frames[f].type, expected[f].type) << toString(m.frames[f].type);
    EXPECT_EQ(m.frames[f].parent_joint, expected[f].parent_joint);
  }
}

::testing::AssertionResult near(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected,
                                double tol = 1e-12) {
  if (actual.rows() != expected.rows() || actual.cols() != expected.cols())
    return ::testing::AssertionFailure() << "shape mismatch";
  if ((actual - expected).cwiseAbs().maxCoeff() <= tol) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "\nactual:\n" << actual << "\nexpected:\n" << expected;
}

// URDF rpy: fixed-axis roll about x, then pitch about y, then yaw about z.
Eigen::Matrix3d rpy(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// --- joint order and q/v layout ---------------------------------------------------------

TEST(UrdfLoader, JointsAreDepthFirstWithChildrenSortedByJointName) {
  Model m = loadUrdfString(kTree);
  EXPECT_EQ(m.name, "tree");
  EXPECT_EQ(m.root, RootJoint::Fixed);
  EXPECT_EQ(m.jointNames(),
            (std::vector<std::string>{"a_joint", "a2_joint", "b_joint", "b_tool_joint", "c_joint"}));
  std::vector<int> parents;
  for (const Joint& j : m.joints) parents.push_back(j.parent);
  EXPECT_EQ(parents, (std::vector<int>{-1, 0, -1, 2, -1}));
  EXPECT_EQ(m.subtree_end, (std::vector<int>{2, 2, 4, 4, 5}));
  EXPECT_TRUE(m.supports(0, 1));
  EXPECT_TRUE(m.supports(2, 3));
  EXPECT_FALSE(m.supports(0, 2));
  EXPECT_FALSE(m.supports(3, 2));
  EXPECT_EQ(m.bodies.size(), m.joints.size());
}

TEST(UrdfLoader, QvLayoutWithFixedRoot) {
  Model m = loadUrdfString(kTree);
  EXPECT_EQ(m.nq, 5);
  EXPECT_EQ(m.nv, 5);
  for (int j = 0; j < m.njoints(); ++j) {
    EXPECT_EQ(m.joints[j].idx_q, j);
    EXPECT_EQ(m.joints[j].idx_v, j);
    EXPECT_EQ(m.joints[j].nq, 1);
    EXPECT_EQ(m.joints[j].nv, 1);
  }
}

TEST(UrdfLoader, QvLayoutWithFreeFlyerRoot) {
  Model m = loadUrdfString(kTree, RootJoint::FreeFlyer);
  EXPECT_EQ(m.root, RootJoint::FreeFlyer);
  EXPECT_EQ(m.jointNames(), (std::vector<std::string>{"root_joint", "a_joint", "a2_joint", "b_joint",
                                                      "b_tool_joint", "c_joint"}));
  const Joint& root = m.joints[0];
  EXPECT_EQ(root.type, JointType::FreeFlyer);
  EXPECT_EQ(root.parent, -1);
  EXPECT_EQ(root.nq, 7);
  EXPECT_EQ(root.nv, 6);
  std::vector<int> parents, idx_q, idx_v;
  for (const Joint& j : m.joints) {
    parents.push_back(j.parent);
    idx_q.push_back(j.idx_q);
    idx_v.push_back(j.idx_v);
  }
  EXPECT_EQ(parents, (std::vector<int>{-1, 0, 1, 0, 3, 0}));
  EXPECT_EQ(idx_q, (std::vector<int>{0, 7, 8, 9, 10, 11}));
  EXPECT_EQ(idx_v, (std::vector<int>{0, 6, 7, 8, 9, 10}));
  EXPECT_EQ(m.subtree_end, (std::vector<int>{6, 3, 3, 5, 5, 6}));
  EXPECT_EQ(m.nq, 12);
  EXPECT_EQ(m.nv, 11);
  for (int j = 1; j < m.njoints(); ++j) EXPECT_TRUE(m.supports(0, j));
}

// --- frames ----------------------------------------------------------------------------

TEST(UrdfLoader, FramesWithFixedRoot) {
  Model m = loadUrdfString(kTree);
  using F = FrameType;
  expectFrames(m, {{"universe", F::FixedJoint, -1},
                   {"base", F::Body, -1},
                   {"a_joint", F::Joint, 0},
                   {"link_z", F::Body, 0},
                   {"a2_joint", F::Joint, 1},
                   {"a2_link", F::Body, 1},
                   {"b_joint", F::Joint, 2},
                   {"link_y", F::Body, 2},
                   {"b_fixed", F::FixedJoint, 2},
                   {"b_tool", F::Body, 2},
                   {"b_tool_joint", F::Joint, 3},
                   {"b_tip", F::Body, 3},
                   {"c_joint", F::Joint, 4},
                   {"link_x", F::Body, 4}});
}

TEST(UrdfLoader, FramesWithFreeFlyerRoot) {
  Model m = loadUrdfString(kTree, RootJoint::FreeFlyer);
  using F = FrameType;
  expectFrames(m, {{"universe", F::FixedJoint, -1},
                   {"root_joint", F::Joint, 0},
                   {"base", F::Body, 0},
                   {"a_joint", F::Joint, 1},
                   {"link_z", F::Body, 1},
                   {"a2_joint", F::Joint, 2},
                   {"a2_link", F::Body, 2},
                   {"b_joint", F::Joint, 3},
                   {"link_y", F::Body, 3},
                   {"b_fixed", F::FixedJoint, 3},
                   {"b_tool", F::Body, 3},
                   {"b_tool_joint", F::Joint, 4},
                   {"b_tip", F::Body, 4},
                   {"c_joint", F::Joint, 5},
                   {"link_x", F::Body, 5}});
}

TEST(UrdfLoader, PlacementsOfJointsAndFrames) {
  Model m = loadUrdfString(kTree);
  // A moving joint's frame and its link's frame are the joint frame itself.
  for (const char* name : {"b_joint", "link_y", "universe", "base"})
    EXPECT_TRUE(near(m.frames[m.frameIndex(name)].placement.translation, Eigen::Vector3d::Zero())) << name;
  const Joint& b = m.joints[m.jointIndex("b_joint")];
  Eigen::Matrix3d rz90;
  rz90 << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  EXPECT_EQ(b.placement.rotation, rz90);  // exact: pi/2 is snapped
  EXPECT_TRUE(near(b.placement.translation, Eigen::Vector3d(0, 0.2, 0)));
  // The fixed joint and the link it carries sit at its origin in b_joint's frame...
  for (const char* name : {"b_fixed", "b_tool"}) {
    const Frame& f = m.frames[m.frameIndex(name)];
    EXPECT_TRUE(near(f.placement.translation, Eigen::Vector3d(0, 0, 0.5))) << name;
    EXPECT_EQ(f.placement.rotation, Eigen::Matrix3d::Identity()) << name;
  }
  // ...and the joint beyond it is placed through it.
  const Joint& tool = m.joints[m.jointIndex("b_tool_joint")];
  EXPECT_EQ(tool.parent, m.jointIndex("b_joint"));
  EXPECT_TRUE(near(tool.placement.translation, Eigen::Vector3d(0.05, 0, 0.5)));
  EXPECT_TRUE(near(m.joints[m.jointIndex("a2_joint")].placement.translation, Eigen::Vector3d(0, 0, 0.2)));
  EXPECT_TRUE(near(m.joints[m.jointIndex("c_joint")].placement.translation, Eigen::Vector3d(0, 0, 0.3)));
}

// --- bodies ----------------------------------------------------------------------------

TEST(UrdfLoader, RootLinkMassBelongsToTheFreeFlyerOnly) {
  Model fixed = loadUrdfString(kTree);
  double total = 0;
  for (const auto& body : fixed.bodies) total += body.mass;
  EXPECT_DOUBLE_EQ(total, 1.0);  // link_x only: the base is welded to the world
  EXPECT_DOUBLE_EQ(fixed.bodies[fixed.jointIndex("c_joint")].mass, 1.0);
  EXPECT_EQ(fixed.bodies[fixed.jointIndex("a_joint")].mass, 0.0);

  Model floating = loadUrdfString(kTree, RootJoint::FreeFlyer);
  const Inertia<double>& base = floating.bodies[0];
  EXPECT_DOUBLE_EQ(base.mass, 3.0);
  EXPECT_TRUE(near(base.lever, Eigen::Vector3d(0.01, 0.02, 0.03)));
  EXPECT_TRUE(near(base.inertia, Eigen::Vector3d(0.3, 0.2, 0.1).asDiagonal().toDenseMatrix()));
}

// An arm link and a hand fixed to it, both with rotated inertial frames, the fixed joint
// rotated too; a massless tool-centre frame beyond. Checked against the composite body
// computed here directly: masses add, the centre of mass is the mass-weighted mean, and
// each rotational inertia is rotated into the joint frame and shifted to the common
// centre of mass by the parallel-axis theorem, I + m (|d|^2 1 - d d^T).
const std::string kMerge = R"(<robot name="merge">
  <link name="base"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/>
    <child link="arm"/>
    <origin xyz="0 0 1"/>
    <axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" effort="50" velocity="3"/>
  </joint>
  <link name="arm">
    <inertial>
      <origin xyz="0.1 0.02 -0.03" rpy="0.3 -0.2 0.5"/>
      <mass value="2"/>
      <inertia ixx="0.05" ixy="0.001" ixz="-0.002" iyy="0.04" iyz="0.003" izz="0.03"/>
    </inertial>
  </link>
  <joint name="wrist_fixed" type="fixed">
    <parent link="arm"/>
    <child link="hand"/>
    <origin xyz="0.4 -0.1 0.05" rpy="-0.7 0.4 1.1"/>
  </joint>
  <link name="hand">
    <inertial>
      <origin xyz="0.03 0.01 0.02" rpy="1.2 0.1 -0.4"/>
      <mass value="0.7"/>
      <inertia ixx="0.002" ixy="0.0001" ixz="0" iyy="0.003" iyz="-0.0002" izz="0.0025"/>
    </inertial>
  </link>
  <joint name="tcp_fixed" type="fixed">
    <parent link="hand"/>
    <child link="tcp"/>
    <origin xyz="0 0 0.12"/>
  </joint>
  <link name="tcp"/>
</robot>
)";

TEST(UrdfLoader, FixedJointsMergeMassComAndInertia) {
  Model m = loadUrdfString(kMerge);
  ASSERT_EQ(m.njoints(), 1);
  ASSERT_EQ(m.bodies.size(), 1u);

  Eigen::Matrix3d arm_inertia, hand_inertia;
  arm_inertia << 0.05, 0.001, -0.002, 0.001, 0.04, 0.003, -0.002, 0.003, 0.03;
  hand_inertia << 0.002, 0.0001, 0, 0.0001, 0.003, -0.0002, 0, -0.0002, 0.0025;
  const double m1 = 2.0, m2 = 0.7;
  // Arm: its link frame is the joint frame.
  const Eigen::Matrix3d r1 = rpy(0.3, -0.2, 0.5);
  const Eigen::Vector3d c1(0.1, 0.02, -0.03);
  const Eigen::Matrix3d i1 = r1 * arm_inertia * r1.transpose();
  // Hand: its link frame sits at the fixed joint's origin.
  const Eigen::Matrix3d rw = rpy(-0.7, 0.4, 1.1);
  const Eigen::Vector3d pw(0.4, -0.1, 0.05);
  const Eigen::Matrix3d r2 = rw * rpy(1.2, 0.1, -0.4);
  const Eigen::Vector3d c2 = rw * Eigen::Vector3d(0.03, 0.01, 0.02) + pw;
  const Eigen::Matrix3d i2 = r2 * hand_inertia * r2.transpose();

  const double mass = m1 + m2;
  const Eigen::Vector3d com = (m1 * c1 + m2 * c2) / mass;
  auto shift = [](double mi, const Eigen::Vector3d& d) {
    return mi * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  };
  const Eigen::Matrix3d inertia = i1 + shift(m1, c1 - com) + i2 + shift(m2, c2 - com);

  const Inertia<double>& body = m.bodies[0];
  EXPECT_NEAR(body.mass, mass, 1e-14);
  EXPECT_TRUE(near(body.lever, com, 1e-14));
  EXPECT_TRUE(near(body.inertia, inertia, 1e-14));

  // The merged links keep their frames, on the moving joint, where they were.
  const Frame& wrist = m.frames[m.frameIndex("wrist_fixed")];
  const Frame& hand = m.frames[m.frameIndex("hand")];
  const Frame& tcp = m.frames[m.frameIndex("tcp")];
  for (const Frame* f : {&wrist, &hand, &tcp}) EXPECT_EQ(f->parent_joint, 0) << f->name;
  EXPECT_EQ(wrist.type, FrameType::FixedJoint);
  EXPECT_EQ(hand.type, FrameType::Body);
  EXPECT_EQ(tcp.type, FrameType::Body);
  EXPECT_EQ(m.frames[m.frameIndex("tcp_fixed")].type, FrameType::FixedJoint);
  EXPECT_TRUE(near(wrist.placement.rotation, rw));
  EXPECT_TRUE(near(wrist.placement.translation, pw));
  EXPECT_TRUE(near(hand.placement.rotation, rw));
  EXPECT_TRUE(near(hand.placement.translation, pw));
  EXPECT_TRUE(near(tcp.placement.rotation, rw));
  EXPECT_TRUE(near(tcp.placement.translation, pw + rw * Eigen::Vector3d(0, 0, 0.12)));
}

TEST(UrdfLoader, FixedChildOfTheRootMergesIntoTheFreeFlyer) {
  // The same arm, hung from a free-flying base through a fixed joint: the arm's mass
  // joins the base body.
  const std::string xml = R"(<robot name="ff">
  <link name="torso">
    <inertial><mass value="5"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
  </link>
  <joint name="head_fixed" type="fixed">
    <parent link="torso"/><child link="head"/><origin xyz="0 0 0.6"/>
  </joint>
  <link name="head">
    <inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
  </link>
</robot>)";
  Model m = loadUrdfString(xml, RootJoint::FreeFlyer);
  ASSERT_EQ(m.njoints(), 1);
  const Inertia<double>& body = m.bodies[0];
  EXPECT_DOUBLE_EQ(body.mass, 6.0);
  EXPECT_TRUE(near(body.lever, Eigen::Vector3d(0, 0, 0.1)));
  // Shifts: torso 0.1 m, head 0.5 m from the composite com along z.
  Eigen::Matrix3d expected = Eigen::Matrix3d::Identity() * 1.1;
  expected(0, 0) += 5 * 0.01 + 1 * 0.25;
  expected(1, 1) += 5 * 0.01 + 1 * 0.25;
  EXPECT_TRUE(near(body.inertia, expected));
  EXPECT_EQ(m.frames[m.frameIndex("head")].parent_joint, 0);

  // Without the free-flyer nothing moves, and there is no joint at all.
  Model fixed = loadUrdfString(xml);
  EXPECT_EQ(fixed.njoints(), 0);
  EXPECT_EQ(fixed.nq, 0);
  EXPECT_EQ(fixed.nv, 0);
  EXPECT_EQ(fixed.frames[fixed.frameIndex("head")].parent_joint, -1);
}

// --- joint kinds and limits --------------------------------------------------------------

TEST(UrdfLoader, ContinuousJointIsUnbounded) {
  Model m = loadUrdfString(kTree);
  const Joint& a = m.joints[m.jointIndex("a_joint")];
  EXPECT_EQ(a.type, JointType::Revolute);
  EXPECT_TRUE(a.continuous);
  EXPECT_EQ(a.nq, 1);
  EXPECT_EQ(a.nv, 1);
  EXPECT_EQ(a.lower[0], -kInf);
  EXPECT_EQ(a.upper[0], kInf);
  EXPECT_EQ(a.velocity_limit[0], kInf);
  EXPECT_EQ(a.effort_limit[0], kInf);
  EXPECT_FALSE(m.joints[m.jointIndex("b_joint")].continuous);
}

TEST(UrdfLoader, ContinuousJointKeepsVelocityAndEffortButNoPositionLimits) {
  const std::string xml = R"(<robot name="wheel">
  <link name="base"/>
  <joint name="wheel" type="continuous">
    <parent link="base"/><child link="rim"/>
    <limit lower="-1" upper="1" effort="7" velocity="12"/>
  </joint>
  <link name="rim"/>
</robot>)";
  const Model m = loadUrdfString(xml);
  const Joint& j = m.joints.at(0);
  EXPECT_TRUE(j.continuous);
  EXPECT_EQ(j.lower[0], -kInf);
  EXPECT_EQ(j.upper[0], kInf);
  EXPECT_EQ(j.velocity_limit[0], 12.0);
  EXPECT_EQ(j.effort_limit[0], 7.0);
}

TEST(UrdfLoader, PrismaticJoint) {
  Model m = loadUrdfString(kTree);
  const Joint& p = m.joints[m.jointIndex("a2_joint")];
  EXPECT_EQ(p.type, JointType::Prismatic);
  EXPECT_FALSE(p.continuous);
  EXPECT_EQ(p.axis_kind, AxisKind::X);
  EXPECT_EQ(p.nq, 1);
  EXPECT_EQ(p.nv, 1);
  EXPECT_EQ(p.lower[0], -0.5);
  EXPECT_EQ(p.upper[0], 0.25);
  EXPECT_EQ(p.velocity_limit[0], 0.5);
  EXPECT_EQ(p.effort_limit[0], 100.0);
}

TEST(UrdfLoader, LimitsAreQueryable) {
  Model m = loadUrdfString(kTree);
  // Joints: a (continuous), a2 (prismatic), b, b_tool, c.
  Eigen::VectorXd lower(5), upper(5), velocity(5), effort(5);
  lower << -kInf, -0.5, -1, -0.5, -3;
  upper << kInf, 0.25, 2, 0.5, 3;
  velocity << kInf, 0.5, 4, 6, 3;
  effort << kInf, 100, 20, 5, 30;
  EXPECT_EQ(m.lowerPositionLimit(), lower);
  EXPECT_EQ(m.upperPositionLimit(), upper);
  EXPECT_EQ(m.velocityLimit(), velocity);
  EXPECT_EQ(m.effortLimit(), effort);

  const Joint& c = m.joints[m.jointIndex("c_joint")];
  EXPECT_EQ(c.damping[0], 0.5);
  EXPECT_EQ(c.friction[0], 0.25);
  EXPECT_EQ(m.joints[m.jointIndex("b_joint")].damping[0], 0.0);

  Model ff = loadUrdfString(kTree, RootJoint::FreeFlyer);
  Eigen::VectorXd ff_lower(12), ff_upper(12), ff_velocity(11), ff_effort(11);
  ff_lower << Eigen::VectorXd::Constant(7, -kInf), lower;
  ff_upper << Eigen::VectorXd::Constant(7, kInf), upper;
  ff_velocity << Eigen::VectorXd::Constant(6, kInf), velocity;
  ff_effort << Eigen::VectorXd::Constant(6, kInf), effort;
  EXPECT_EQ(ff.lowerPositionLimit(), ff_lower);
  EXPECT_EQ(ff.upperPositionLimit(), ff_upper);
  EXPECT_EQ(ff.velocityLimit(), ff_velocity);
  EXPECT_EQ(ff.effortLimit(), ff_effort);
}

// --- axes and rotations ----------------------------------------------------------------

std::string indexed(const char* prefix, size_t i) {
  std::string name = prefix;
  name += std::to_string(i);
  return name;
}

std::string axisRobot() {
  // One revolute joint per axis spelling, all children of the base, named in order.
  const std::vector<std::string> axes = {"0 0 2", "0 3 0", "0.5 0 0", "", "0 0 -1", "1 1 0", "1e-17 0 1"};
  std::string xml = "<robot name=\"axes\">\n  <link name=\"base\"/>\n";
  for (size_t i = 0; i < axes.size(); ++i) {
    std::string n = std::to_string(i);
    xml +=
        "  <joint name=\"j" + n + "\" type=\"revolute\"><parent link=\"base\"/><child link=\"l" + n + "\"/>";
    if (!axes[i].empty()) xml += "<axis xyz=\"" + axes[i] + "\"/>";
    xml += "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n  <link name=\"l" + n +
           "\"/>\n";
  }
  return xml + "</robot>\n";
}

TEST(UrdfLoader, AxesAreNormalisedAndClassified) {
  Model m = loadUrdfString(axisRobot());
  ASSERT_EQ(m.njoints(), 7);
  auto axis = [&](int j) { return m.joints[m.jointIndex(indexed("j", j))]; };
  EXPECT_EQ(axis(0).axis, Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(axis(0).axis_kind, AxisKind::Z);
  EXPECT_EQ(axis(1).axis, Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(axis(1).axis_kind, AxisKind::Y);
  EXPECT_EQ(axis(2).axis, Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(axis(2).axis_kind, AxisKind::X);
  // No <axis>: URDF's default, x.
  EXPECT_EQ(axis(3).axis, Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(axis(3).axis_kind, AxisKind::X);
  // Negative axes are not aligned kinds.
  EXPECT_EQ(axis(4).axis, Eigen::Vector3d(0, 0, -1));
  EXPECT_EQ(axis(4).axis_kind, AxisKind::Unaligned);
  const Eigen::Vector3d diagonal = axis(5).axis;
  EXPECT_NEAR(diagonal.norm(), 1.0, 1e-15);
  EXPECT_NEAR(diagonal.x(), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(diagonal.y(), std::sqrt(0.5), 1e-15);
  EXPECT_EQ(diagonal.z(), 0.0);
  EXPECT_EQ(axis(5).axis_kind, AxisKind::Unaligned);
  // Rounding noise below the snap tolerance vanishes.
  EXPECT_EQ(axis(6).axis, Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(axis(6).axis_kind, AxisKind::Z);
}

TEST(UrdfLoader, RightAngleRotationsAreExact) {
  struct Case {
    const char* rpy;
    double roll, pitch, yaw;
    bool snapped;
  };
  const double pi = 2 * kHalfPi;
  const std::vector<Case> cases = {
      {"1.5707963267948966 0 0", kHalfPi, 0, 0, true},
      {"0 0 3.141592653589793", 0, 0, pi, true},
      {"1.5707963267948966 1.5707963267948966 0", kHalfPi, kHalfPi, 0, true},
      {"-1.5707963267948966 0 3.141592653589793", -kHalfPi, 0, pi, true},
      {"0 -1.5707963267948966 -1.5707963267948966", 0, -kHalfPi, -kHalfPi, true},
      {"0.3 0 0", 0.3, 0, 0, false},
  };
  std::string xml = "<robot name=\"rotations\">\n  <link name=\"base\"/>\n";
  for (size_t i = 0; i < cases.size(); ++i) {
    std::string n = std::to_string(i);
    xml += "  <joint name=\"f" + n + "\" type=\"fixed\"><parent link=\"base\"/><child link=\"l" + n +
           "\"/><origin rpy=\"" + cases[i].rpy + "\"/></joint>\n  <link name=\"l" + n + "\"/>\n";
  }
  // A moving joint's placement is cleaned the same way.
  xml += R"(  <joint name="hinge" type="revolute"><parent link="base"/><child link="flap"/>
    <origin xyz="0 0 0" rpy="1.5707963267948966 0 0"/><limit effort="1" velocity="1"/></joint>
  <link name="flap"/>
</robot>)";
  Model m = loadUrdfString(xml);
  for (size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE(cases[i].rpy);
    const Eigen::Matrix3d r = rpy(cases[i].roll, cases[i].pitch, cases[i].yaw);
    const Eigen::Matrix3d& actual = m.frames[m.frameIndex(indexed("f", i))].placement.rotation;
    if (cases[i].snapped) {
      const Eigen::Matrix3d exact = r.array().round().matrix();
      ASSERT_TRUE(near(r, exact, 1e-12));  // the case really is a signed permutation
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) EXPECT_EQ(actual(a, b), exact(a, b)) << "entry (" << a << "," << b << ")";
    } else {
      EXPECT_TRUE(near(actual, r, 1e-15));
      EXPECT_NE(actual(1, 1), 1.0);
    }
  }
  Eigen::Matrix3d rx90;
  rx90 << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  EXPECT_EQ(m.joints[m.jointIndex("hinge")].placement.rotation, rx90);
}

TEST(UrdfLoader, TabsAndLineBreaksInsideNumberListsAreSpaces) {
  const std::string xml =
      "<robot name=\"ws\">\n  <link name=\"base\"/>\n"
      "  <joint name=\"j\" type=\"prismatic\"><parent link=\"base\"/><child link=\"l\"/>\n"
      "    <origin xyz=\"0.1\t0.2\n      0.3\" rpy=\"0\r\n0 0\"/><axis xyz=\"0\t1\t0\"/>\n"
      "    <limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n"
      "  <link name=\"l\"/>\n</robot>\n";
  Model m = loadUrdfString(xml);
  ASSERT_EQ(m.njoints(), 1);
  EXPECT_EQ(m.joints[0].placement.translation, Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(m.joints[0].axis_kind, AxisKind::Y);
}

// --- look-ups --------------------------------------------------------------------------

TEST(UrdfLoader, FindJointAndFrame) {
  Model m = loadUrdfString(kTree);
  EXPECT_EQ(m.findJoint("b_joint"), 2);
  EXPECT_EQ(m.findJoint("c_joint"), 4);
  EXPECT_EQ(m.findJoint("b_fixed"), std::nullopt);  // fixed joints are frames only
  EXPECT_EQ(m.findJoint("link_y"), std::nullopt);
  EXPECT_EQ(m.findJoint("nonexistent"), std::nullopt);
  EXPECT_EQ(m.findFrame("universe"), 0);
  EXPECT_EQ(m.findFrame("b_fixed"), 8);
  EXPECT_EQ(m.findFrame("b_joint"), 6);
  EXPECT_EQ(m.findFrame("link_y"), 7);
  EXPECT_EQ(m.findFrame("nonexistent"), std::nullopt);
  EXPECT_EQ(m.jointIndex("a2_joint"), 1);
  EXPECT_EQ(m.frameIndex("b_tip"), 11);
  EXPECT_EQ(m.frameNames().size(), m.frames.size());
  EXPECT_EQ(m.frameNames()[9], "b_tool");

  Model ff = loadUrdfString(kTree, RootJoint::FreeFlyer);
  EXPECT_EQ(ff.findJoint("root_joint"), 0);
  EXPECT_EQ(ff.findFrame("root_joint"), 1);
  EXPECT_EQ(ff.jointIndex("b_joint"), 3);
}

TEST(UrdfLoader, UnknownNamesThrowNamingThem) {
  Model m = loadUrdfString(kTree);
  try {
    m.jointIndex("b_fixed");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'b_fixed'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("tree"), std::string::npos) << e.what();
  }
  try {
    m.frameIndex("elbow");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'elbow'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace robodiff
