// User functions against Pinocchio's values in ../shared/golden, chained by hand here:
// a semi-implicit Euler step's Jacobians from dddq_dq, dddq_dv and M^-1 (fixed and
// floating base), a tracking cost's value and gradient from the frame placements and
// LOCAL_WORLD_ALIGNED Jacobians, and the forward-dynamics step's Jacobian w.r.t. q in
// the tangent space of a free-flyer.
#include <Eigen/LU>

#include <gtest/gtest.h>

#include "robodiff/codegen/interpreter.hpp"
#include "robodiff/functions/evaluation.hpp"
#include "robodiff/functions/function_builder.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "support/golden.hpp"
#include "support/test_paths.hpp"

namespace robodiff {
namespace {

using testing::matricesAgree;

constexpr double kDt = 0.01;

const char* kStep = R"js({
  "inputs": {"q": "configuration", "v": "nv", "u": "nv", "dt": {"fixed": [0.01]}},
  "define": {"v_next": "v + dt * aba(q, v, u)", "q_next": "integrate(q, dt * v_next)"},
  "outputs": [
    {"name": "v_next", "kind": "value", "of": "v_next"},
    {"name": "dv_next", "kind": "jacobian", "of": "v_next", "wrt": ["q", "v", "u"]}
  ]})js";

class UserGolden : public ::testing::TestWithParam<std::string> {};

// A value-only step: aba's value built as ABA and as M^-1 (tau - nle) by M's tree
// factors, both against Pinocchio's ddq; the default keeps the one with fewer operations.
TEST_P(UserGolden, AValueOnlyStepMatchesPinocchioWithEitherAbaAndKeepsTheSmaller) {
  ROBODIFF_REQUIRE_SHARED(shared);
  const testing::GoldenRobot golden = testing::loadGolden(shared, GetParam());
  const Model model = loadUrdfFile(golden.urdf.string(), golden.free_flyer ? RootJoint::FreeFlyer : RootJoint::Fixed);
  const FunctionSpec spec = parseFunctionSpec(R"js({
    "inputs": {"q": "configuration", "v": "nv", "u": "nv", "dt": {"fixed": [0.01]}},
    "outputs": [{"name": "v_next", "kind": "value", "of": "v + dt * aba(q, v, u)"}]})js");
  FunctionBuilderOptions articulated_options, factors_options;
  articulated_options.aba_value = AbaValueMethod::Articulated;
  factors_options.aba_value = AbaValueMethod::Factors;
  const BuiltFunction articulated = buildFunction(model, spec, articulated_options);
  const BuiltFunction factors = buildFunction(model, spec, factors_options);
  const BuiltFunction chosen = buildFunction(model, spec);
  const std::size_t a_ops = builtOperations(articulated), f_ops = builtOperations(factors);
  EXPECT_NE(a_ops, f_ops);  // two different traces
  EXPECT_EQ(builtOperations(chosen), std::min(a_ops, f_ops));
  EXPECT_NE(chosen.method.find(f_ops <= a_ops ? "chosen over ABA" : "chosen over M^-1"), std::string::npos) << chosen.method;
  codegen::Interpreter ia(*articulated.graph, articulated.definition), jf(*factors.graph, factors.definition);
  for (std::size_t s = 0; s < golden.samples.size(); s += 5) {
    const testing::GoldenSample& x = golden.samples[s];
    EXPECT_TRUE(matricesAgree(evaluateBlocks(ia, articulated.definition, {x.q, x.v, x.tau})[0], x.v + kDt * x.ddq, 1e-9));
    EXPECT_TRUE(matricesAgree(evaluateBlocks(jf, factors.definition, {x.q, x.v, x.tau})[0], x.v + kDt * x.ddq, 1e-9));
  }
}

TEST_P(UserGolden, EulerStepJacobianIsChainedFromPinocchiosDerivatives) {
  ROBODIFF_REQUIRE_SHARED(shared);
  const testing::GoldenRobot golden = testing::loadGolden(shared, GetParam());
  const Model model = loadUrdfFile(golden.urdf.string(), golden.free_flyer ? RootJoint::FreeFlyer : RootJoint::Fixed);
  const BuiltFunction f = buildFunction(model, parseFunctionSpec(kStep));
  codegen::Interpreter interpreter(*f.graph, f.definition);
  const int n = model.nv;
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  for (std::size_t s = 0; s < golden.samples.size(); s += 5) {
    const testing::GoldenSample& x = golden.samples[s];
    const std::vector<Eigen::VectorXd> out = evaluateBlocks(interpreter, f.definition, {x.q, x.v, x.tau});
    EXPECT_TRUE(matricesAgree(out[0], x.v + kDt * x.ddq, 1e-9));
    const Eigen::MatrixXd J = blockMatrix(f.definition.outputs[1], out[1]);
    EXPECT_TRUE(matricesAgree(J.leftCols(n), kDt * x.dddq_dq, 1e-8));
    EXPECT_TRUE(matricesAgree(J.middleCols(n, n), I + kDt * x.dddq_dv, 1e-8));
    EXPECT_TRUE(matricesAgree(J.rightCols(n), kDt * x.M.inverse(), 1e-8));
  }
}

TEST_P(UserGolden, TrackingCostFromFramePlacementsAndJacobians) {
  ROBODIFF_REQUIRE_SHARED(shared);
  const testing::GoldenRobot golden = testing::loadGolden(shared, GetParam());
  const Model model = loadUrdfFile(golden.urdf.string(), golden.free_flyer ? RootJoint::FreeFlyer : RootJoint::Fixed);
  const std::string frame = golden.ee_frames.front();
  const FunctionSpec spec = parseFunctionSpec(R"js({
    "inputs": {"q": "configuration", "tau": "nv", "target": 3},
    "define": {"e": "frame_position(q, ')js" + frame + R"js(') - target", "cost": "sumsq(e) + 1e-3 * sumsq(tau)"},
    "outputs": [
      {"name": "cost", "kind": "value", "of": "cost"},
      {"name": "grad", "kind": "gradient", "of": "cost", "wrt": ["q", "tau"]},
      {"name": "rotation", "kind": "value", "of": "frame_rotation(q, ')js" + frame + R"js(')"}
    ]})js");
  const BuiltFunction f = buildFunction(model, spec);
  codegen::Interpreter interpreter(*f.graph, f.definition);
  const Eigen::Vector3d target(0.3, -0.2, 0.5);
  for (std::size_t s = 0; s < golden.samples.size(); s += 5) {
    const testing::GoldenSample& x = golden.samples[s];
    const std::vector<Eigen::VectorXd> out = evaluateBlocks(interpreter, f.definition, {x.q, x.tau, target});
    const SE3<double>& placement = x.frame_placements.at(frame);
    const Eigen::Vector3d e = placement.translation - target;
    const Eigen::MatrixXd J = x.ee_jacobian_local_world_aligned.at(frame).topRows(3);
    Eigen::VectorXd grad(2 * model.nv);
    grad << 2 * J.transpose() * e, 2e-3 * x.tau;
    EXPECT_NEAR(out[0][0], e.squaredNorm() + 1e-3 * x.tau.squaredNorm(), 1e-9 * (1 + out[0][0]));
    EXPECT_TRUE(matricesAgree(out[1], grad, 1e-8));
    EXPECT_TRUE(matricesAgree(blockMatrix(f.definition.outputs[2], out[2]), placement.rotation, 1e-9));
  }
}

INSTANTIATE_TEST_SUITE_P(Robots, UserGolden, ::testing::Values("panda", "talos_ff"));

}  // namespace
}  // namespace robodiff
