// Tracing the dynamics algorithms with Sym: the graph, evaluated, equals the double
// algorithm to rounding (1e-12 relative), on generated robots with every joint kind.
#include <random>

#include <gtest/gtest.h>

#include "robodiff/dynamics/all.hpp"
#include "robodiff/model/robot_generator.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/symbolic/tracer.hpp"
#include "support/robot_cases.hpp"
#include "support/golden.hpp"

namespace robodiff::symbolic {
namespace {

using testing::matricesAgree;

using testing::RobotCase;

std::vector<RobotCase> tracingRobotCases() {
  GeneratorOptions quadruped;
  quadruped.kind = RobotKind::Tree;
  quadruped.tree = "quadruped";
  quadruped.seed = 3;
  quadruped.prismatic_fraction = 0.25;
  GeneratorOptions chain;
  chain.joints = 7;
  chain.seed = 11;
  chain.prismatic_fraction = 0.3;
  chain.continuous_fraction = 0.2;
  return {{"quadruped_free_flyer", quadruped, RootJoint::FreeFlyer},
          {"chain7_prismatic", chain, RootJoint::Fixed}};
}

class Tracing : public ::testing::TestWithParam<RobotCase> {
 protected:
  void SetUp() override {
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> u(-1, 1);
    q = randomConfiguration(model, rng);
    v = Eigen::VectorXd::NullaryExpr(model.nv, [&] { return u(rng); });
    a = Eigen::VectorXd::NullaryExpr(model.nv, [&] { return u(rng); });
    tau = Eigen::VectorXd::NullaryExpr(model.nv, [&] { return u(rng); });
  }

  // The traced values of a matrix of Syms at `inputs`, as a matrix of the same shape.
  template <class M> Eigen::MatrixXd evaluate(const Tracer& tracer, const M& m, const Eigen::VectorXd& inputs) {
    std::vector<NodeId> nodes = tracer.outputs(m);
    std::vector<double> values = tracer.graph().evaluate(nodes, {inputs.data(), inputs.data() + inputs.size()});
    Eigen::MatrixXd out(m.rows(), m.cols());
    for (Eigen::Index r = 0, k = 0; r < m.rows(); ++r)
      for (Eigen::Index c = 0; c < m.cols(); ++c) out(r, c) = values[k++];
    return out;
  }

  // q, v and a third block (a or tau) as the tracer's inputs, in that order.
  struct StateInputs {
    VecX<Sym> q, v, third;
  };
  StateInputs addStateInputs(Tracer& tracer, const char* third) const {
    return {tracer.addInputs("q", model.nq), tracer.addInputs("v", model.nv), tracer.addInputs(third, model.nv)};
  }

  Model model = loadUrdfString(generateRobotUrdf(GetParam().options), GetParam().root, GetParam().label);
  Eigen::VectorXd q, v, a, tau;
  // Each test traces into its own graph.
  Graph graph;
  Tracer tracer{graph};
  Data<Sym> ds{model};
  Data<double> dd{model};
};

Eigen::VectorXd tracedStack(std::initializer_list<const Eigen::VectorXd*> parts) {
  Eigen::Index n = 0;
  for (auto* p : parts) n += p->size();
  Eigen::VectorXd out(n);
  n = 0;
  for (auto* p : parts) {
    out.segment(n, p->size()) = *p;
    n += p->size();
  }
  return out;
}

TEST_P(Tracing, Rnea) {
  const StateInputs in = addStateInputs(tracer, "a");
  EXPECT_TRUE(matricesAgree(evaluate(tracer, rnea(model, ds, in.q, in.v, in.third), tracedStack({&q, &v, &a})),
                            rnea(model, dd, q, v, a), 1e-12));
}

TEST_P(Tracing, Aba) {
  const StateInputs in = addStateInputs(tracer, "tau");
  EXPECT_TRUE(matricesAgree(evaluate(tracer, aba(model, ds, in.q, in.v, in.third), tracedStack({&q, &v, &tau})),
                            aba(model, dd, q, v, tau), 1e-12));
}

TEST_P(Tracing, CrbaAndGravity) {
  VecX<Sym> qs = tracer.addInputs("q", model.nq);
  EXPECT_TRUE(matricesAgree(evaluate(tracer, crba(model, ds, qs), q), crba(model, dd, q), 1e-12));
  EXPECT_TRUE(matricesAgree(evaluate(tracer, computeGeneralizedGravity(model, ds, qs), q),
                            computeGeneralizedGravity(model, dd, q), 1e-12));
}

TEST_P(Tracing, Regressor) {
  const StateInputs in = addStateInputs(tracer, "a");
  EXPECT_TRUE(matricesAgree(
      evaluate(tracer, jointTorqueRegressor(model, ds, in.q, in.v, in.third), tracedStack({&q, &v, &a})),
      jointTorqueRegressor(model, dd, q, v, a), 1e-12));
}

TEST_P(Tracing, KinematicsAndFrameJacobians) {
  VecX<Sym> qs = tracer.addInputs("q", model.nq);
  forwardKinematics(model, ds, qs);
  updateFramePlacements(model, ds);
  forwardKinematics(model, dd, q);
  updateFramePlacements(model, dd);
  for (int f = 0; f < model.nframes(); ++f) {
    SCOPED_TRACE(model.frames[f].name);
    EXPECT_TRUE(matricesAgree(evaluate(tracer, ds.oMf[f].rotation, q), dd.oMf[f].rotation, 1e-12));
    EXPECT_TRUE(matricesAgree(evaluate(tracer, ds.oMf[f].translation, q), dd.oMf[f].translation, 1e-12));
  }
  const int tool = model.nframes() - 1;
  for (ReferenceFrame ref : {ReferenceFrame::Local, ReferenceFrame::World, ReferenceFrame::LocalWorldAligned}) {
    SCOPED_TRACE(toString(ref));
    EXPECT_TRUE(matricesAgree(evaluate(tracer, computeFrameJacobian(model, ds, qs, tool, ref), q),
                              computeFrameJacobian(model, dd, q, tool, ref), 1e-12));
  }
}

// ABA's value by M's tree factors: the same accelerations as ABA, with one division per
// pivot (1 / D_k, shared by the factors, the solve and M^-1), not one per entry of L.
TEST_P(Tracing, ForwardDynamicsByFactorsDividesOncePerPivot) {
  const StateInputs in = addStateInputs(tracer, "tau");
  auto divisions = [this] {
    int n = 0;
    for (NodeId id = 0; id < graph.size(); ++id) n += graph.node(id).op == Op::Div;
    return n;
  };
  const VecX<Sym> bias = in.third - nonLinearEffects(model, ds, in.q, in.v);
  MatX<Sym> factors = crba(model, ds, in.q);
  const int before = divisions();
  const std::vector<int> lambda = dofParents(model);
  factorizeMassMatrix(lambda, factors);
  const VecX<Sym> ddq = solveWithFactors(lambda, factors, bias);
  inverseFromFactors(lambda, factors);
  EXPECT_LE(divisions() - before, model.nv);
  EXPECT_TRUE(matricesAgree(evaluate(tracer, ddq, tracedStack({&q, &v, &tau})), aba(model, dd, q, v, tau), 1e-12));
}

INSTANTIATE_TEST_SUITE_P(Robots, Tracing, ::testing::ValuesIn(tracingRobotCases()),
                         [](const auto& info) { return info.param.label; });

}  // namespace
}  // namespace robodiff::symbolic
