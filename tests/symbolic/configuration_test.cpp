// integrateSecondOrder: q0 (+) dq to second order, the configuration the tangent-space
// derivatives are traced at; and the node limit met while tracing a real algorithm.
#include <random>

#include <gtest/gtest.h>

#include "robodiff/dynamics/all.hpp"
#include "robodiff/model/robot_generator.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/symbolic/configuration.hpp"
#include "robodiff/symbolic/differentiation.hpp"
#include "robodiff/symbolic/tracer.hpp"

namespace robodiff::symbolic {
namespace {

Model freeFlyerQuadruped() {
  GeneratorOptions options;
  options.kind = RobotKind::Tree;
  options.tree = "quadruped";
  options.seed = 2;
  return loadUrdfString(generateRobotUrdf(options), RootJoint::FreeFlyer, "quadruped");
}

TEST(IntegrateSecondOrder, AgreesWithIntegrateToThirdOrder) {
  const Model model = freeFlyerQuadruped();
  std::mt19937_64 rng(4);
  const Eigen::VectorXd q0 = randomConfiguration(model, rng);
  const Eigen::VectorXd dir = Eigen::VectorXd::LinSpaced(model.nv, -1.0, 0.8);
  auto error = [&](double h) {
    return (integrateSecondOrder<double>(model, q0, h * dir) - integrate(model, q0, h * dir)).norm();
  };
  const double e1 = error(1e-2), e2 = error(5e-3);
  EXPECT_LT(e1, 1e-5);
  EXPECT_GT(e1 / e2, 6.0) << "halving the step should divide an O(h^3) error by ~8";
  EXPECT_EQ(integrateSecondOrder<double>(model, q0, Eigen::VectorXd::Zero(model.nv)), q0);
}

TEST(NodeLimit, TracingPastTheLimitIsAResourceError) {
  const Model model = freeFlyerQuadruped();
  Graph graph;
  graph.setNodeLimit(500);
  Tracer tracer(graph);
  const VecX<Sym> q = tracer.addInputs("q", model.nq), v = tracer.addInputs("v", model.nv),
                  a = tracer.addInputs("a", model.nv);
  Data<Sym> data(model);
  EXPECT_THROW(rnea(model, data, q, v, a), GraphTooLarge);
  EXPECT_LE(graph.size(), 500u);

  // The same while differentiating: the value fits, its Jacobian does not.
  Graph g2;
  Tracer t2(g2);
  const VecX<Sym> q2 = t2.addInputs("q", model.nq), v2 = t2.addInputs("v", model.nv), a2 = t2.addInputs("a", model.nv);
  Data<Sym> d2(model);
  const std::vector<NodeId> tau = t2.outputs(rnea(model, d2, q2, v2, a2));
  g2.setNodeLimit(g2.size() + 100);
  try {
    jacobian(g2, tau, t2.indices({"v"}));
    FAIL() << "no GraphTooLarge";
  } catch (const GraphTooLarge& e) {
    EXPECT_EQ(e.limit(), g2.nodeLimit());
    EXPECT_NE(std::string(e.what()).find(std::to_string(g2.nodeLimit())), std::string::npos);
  }
}

}  // namespace
}  // namespace robodiff::symbolic
