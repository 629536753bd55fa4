// The LOCAL_WORLD_ALIGNED frame Jacobian traced: its linear columns are rotated to the
// world in the steps that end soonest (detail::balancedRotationJoints), so the columns
// of the joints near the frame end sooner than with each column's own world rotation
// R_j, and the values are the same function of q.
#include <algorithm>
#include <random>

#include <gtest/gtest.h>

#include "robodiff/dynamics/jacobian.hpp"
#include "robodiff/model/robot_generator.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/symbolic/tracer.hpp"

namespace robodiff::symbolic {
namespace {

// The longest path to any of `outputs`, in the code generator's rough cycles: 40 for sin
// and cos, 4 for every other operation.
std::uint32_t longestPathInCycles(const Graph& graph, const std::vector<NodeId>& outputs) {
  std::vector<std::uint32_t> end(graph.size(), 0);
  for (NodeId id = 0; id < graph.size(); ++id) {
    const Node& n = graph.node(id);
    if (n.op == Op::Constant || n.op == Op::Input) continue;
    std::uint32_t start = 0;
    for (int a = 0; a < arity(n.op); ++a) start = std::max(start, end[n.args[a]]);
    end[id] = start + (n.op == Op::Sin || n.op == Op::Cos ? 40 : 4);
  }
  std::uint32_t longest = 0;
  for (NodeId o : outputs) longest = std::max(longest, end[o]);
  return longest;
}

// The linear columns as R_j (s x u_j): every column waits for its joint's whole chain of
// world rotations (the form before the balancing). Revolute joints only.
Matrix6X<Sym> eachColumnByItsOwnRotation(const Model& model, const Data<Sym>& data, int frame_index) {
  Matrix6X<Sym> J = Matrix6X<Sym>::Zero(6, model.nv);
  const Frame& frame = model.frames[frame_index];
  Vec3<Sym> to_frame = frame.placement.translation.cast<Sym>();
  for (int j = frame.parent_joint; j >= 0; j = model.joints[j].parent) {
    const Joint& joint = model.joints[j];
    const Mat3<Sym>& R = data.oMi[j].rotation;
    const Vec3<Sym> axis = joint.axis.cast<Sym>();
    J.block<3, 1>(3, joint.idx_v) = R * axis;
    J.block<3, 1>(0, joint.idx_v) = R * Vec3<Sym>(axis.cross(to_frame));
    to_frame = data.liMi[j].act(to_frame);
  }
  return J;
}

struct TracedJacobian {
  std::uint32_t last_column_path;  // the longest path to the linear part of the frame's joint's column
  std::vector<double> at_q;
};

TracedJacobian traceWorldAlignedJacobian(const Model& model, bool balanced) {
  Graph graph;
  Tracer tracer(graph);
  const VecX<Sym> q = tracer.addInputs("q", model.nq);
  Data<Sym> data(model);
  forwardKinematics(model, data, q);
  const int f = model.nframes() - 1;
  const Matrix6X<Sym> J = balanced ? frameJacobian(model, data, f, ReferenceFrame::LocalWorldAligned)
                                   : eachColumnByItsOwnRotation(model, data, f);
  const VecX<Sym> flat = Eigen::Map<const VecX<Sym>>(J.data(), J.size());
  const std::vector<NodeId> outputs = tracer.outputs(flat);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  std::vector<double> input(model.nq);
  for (double& x : input) x = u(rng);
  const int last = model.joints[model.frames[f].parent_joint].idx_v;
  const std::vector<NodeId> last_column(outputs.begin() + 6 * last, outputs.begin() + 6 * last + 3);
  return {longestPathInCycles(graph, last_column), graph.evaluate(outputs, input)};
}

TEST(FrameJacobianLatency, ColumnsAreRotatedToTheWorldInTheStepsThatEndSoonest) {
  GeneratorOptions arm;
  arm.joints = 7;
  arm.seed = 4;
  const Model model = loadUrdfString(generateRobotUrdf(arm));
  const TracedJacobian own = traceWorldAlignedJacobian(model, false);
  const TracedJacobian balanced = traceWorldAlignedJacobian(model, true);
  // Seven joints: the last column waited for seven rotation products after its sin and
  // cos (128 cycles by this count); balanced, 100. (The first column still waits for
  // the offset summed over the whole chain.)
  EXPECT_LT(balanced.last_column_path + 20, own.last_column_path)
      << balanced.last_column_path << " against " << own.last_column_path;
  ASSERT_EQ(balanced.at_q.size(), own.at_q.size());
  for (std::size_t i = 0; i < own.at_q.size(); ++i) EXPECT_NEAR(balanced.at_q[i], own.at_q[i], 1e-12) << i;
  RecordProperty("last_column_path",
                 std::to_string(own.last_column_path) + " -> " + std::to_string(balanced.last_column_path));
}

// The choice itself on the shapes of the anchors' rows: a free-flying base and two
// revolute joints (the free-flying Talos's torso), three revolute joints (a leg).
TEST(FrameJacobianLatency, TheChoiceBalancesTheRotationChainAgainstTheOffsetChain) {
  GeneratorOptions leg;
  leg.joints = 3;
  leg.seed = 2;
  const Model fixed = loadUrdfString(generateRobotUrdf(leg));
  // Joint 2 (the frame's): R_1 (Q_2 w) ends two products after the sin and cos, R_2 w three.
  EXPECT_EQ(detail::balancedRotationJoints(fixed, {0, 1, 2}), (std::vector<int>{0, 1, 1}));
  leg.joints = 2;
  const Model floating = loadUrdfString(generateRobotUrdf(leg), RootJoint::FreeFlyer);
  EXPECT_EQ(detail::balancedRotationJoints(floating, {0, 1, 2}), (std::vector<int>{0, 1, 1}));
}

}  // namespace
}  // namespace robodiff::symbolic
