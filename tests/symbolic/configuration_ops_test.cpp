// integrateConfiguration / differenceConfiguration traced on Sym: the graph computes the
// double version's values, and its derivatives (first and second) are finite and match
// finite differences, also at zero motion where the series branch is taken.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "robodiff/dynamics/configuration.hpp"
#include "robodiff/dynamics/lie_group.hpp"
#include "robodiff/model/robot_generator.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/symbolic/differentiation.hpp"
#include "robodiff/symbolic/hessian.hpp"
#include "robodiff/symbolic/tracer.hpp"

namespace robodiff::symbolic {
namespace {

// Free-flyer, one revolute, one continuous and one prismatic joint.
Model floatingChain() {
  GeneratorOptions options;
  options.kind = RobotKind::Chain;
  options.joints = 3;
  options.seed = 7;
  options.prismatic_fraction = 0.34;
  options.continuous_fraction = 0.33;
  return loadUrdfString(generateRobotUrdf(options), RootJoint::FreeFlyer, "chain3");
}

// A random tangent vector whose free-flyer angular part has norm `angle`.
Eigen::VectorXd randomTangent(const Model& model, std::mt19937_64& rng, double angle) {
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::VectorXd d(model.nv);
  for (int i = 0; i < model.nv; ++i) d[i] = u(rng);
  Eigen::Vector3d w(u(rng), u(rng), u(rng));
  d.segment<3>(3) = angle * w.normalized();  // the root free-flyer's angular velocity
  return d;
}

std::vector<double> stack(const std::vector<Eigen::VectorXd>& parts) {
  std::vector<double> out;
  for (const Eigen::VectorXd& p : parts) out.insert(out.end(), p.data(), p.data() + p.size());
  return out;
}

Eigen::VectorXd evaluate(const Graph& graph, const std::vector<NodeId>& outputs, const std::vector<double>& inputs) {
  const std::vector<double> v = graph.evaluate(outputs, inputs);
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

Eigen::MatrixXd evaluate(const Graph& graph, const Jacobian& jac, const std::vector<double>& inputs) {
  const Eigen::VectorXd v = evaluate(graph, jac.entries, inputs);
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(v.data(), jac.rows,
                                                                                                 jac.cols);
}

// Central differences of f around x, column k along e_k.
template <class F> Eigen::MatrixXd finiteDifferences(F f, const Eigen::VectorXd& x, double h = 1e-5) {
  Eigen::MatrixXd out;
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    Eigen::VectorXd lo = x, hi = x;
    lo[k] -= h;
    hi[k] += h;
    const Eigen::VectorXd col = (f(hi) - f(lo)) / (2 * h);
    if (k == 0) out.resize(col.size(), x.size());
    out.col(k) = col;
  }
  return out;
}

::testing::AssertionResult close(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected, double tol) {
  if (!actual.allFinite()) return ::testing::AssertionFailure() << "not finite:\n" << actual;
  const double err = (actual - expected).lpNorm<Eigen::Infinity>();
  if (err > tol * (1 + expected.lpNorm<Eigen::Infinity>()))
    return ::testing::AssertionFailure() << "error " << err << "\nactual:\n" << actual << "\nexpected:\n" << expected;
  return ::testing::AssertionSuccess();
}

class ConfigurationOps : public ::testing::Test {
 protected:
  Model model = floatingChain();
  std::mt19937_64 rng{11};
  Eigen::VectorXd zero = Eigen::VectorXd::Zero(model.nv);

  Eigen::VectorXd integ(const Eigen::VectorXd& q, const Eigen::VectorXd& dq) const {
    return integrateConfiguration<double>(model, q, dq);
  }
  Eigen::VectorXd diff(const Eigen::VectorXd& q0, const Eigen::VectorXd& q1) const {
    return differenceConfiguration<double>(model, q0, q1);
  }
};

// Rotation angles from zero motion through the series/exact switch (|w| ~ 0.0316) to
// large ones; differences need |w| < pi.
const double kAngles[] = {0.0, 1e-12, 1e-9, 1e-4, 0.0316, 0.0317, 0.5, 2.0, 3.1};

TEST_F(ConfigurationOps, TracedGraphMatchesDouble) {
  Graph graph;
  Tracer tracer(graph);
  const VecX<Sym> q = tracer.addInputs("q", model.nq), dq = tracer.addInputs("dq", model.nv),
                  q1 = tracer.addInputs("q1", model.nq);
  const std::vector<NodeId> integrated = tracer.outputs(integrateConfiguration<Sym>(model, q, dq));
  const std::vector<NodeId> difference = tracer.outputs(differenceConfiguration<Sym>(model, q, q1));
  for (double angle : kAngles) {
    for (int trial = 0; trial < 4; ++trial) {
      const Eigen::VectorXd qv = randomConfiguration(model, rng), dqv = randomTangent(model, rng, 4 * angle);
      // q1: near q (the same angle), far from it, or q itself.
      const Eigen::VectorXd q1v = trial == 0 ? qv : trial == 1 ? randomConfiguration(model, rng)
                                                               : integ(qv, randomTangent(model, rng, angle));
      const std::vector<double> in = stack({qv, dqv, q1v});
      EXPECT_TRUE(close(evaluate(graph, integrated, in), integ(qv, dqv), 1e-12)) << "|w| = " << 4 * angle;
      EXPECT_TRUE(close(evaluate(graph, difference, in), diff(qv, q1v), 1e-12)) << "|w| = " << angle;
    }
  }
}

// difference(q0, integrate(q0, d)) == d: Jacobian I and second derivatives 0, at d = 0 too.
TEST_F(ConfigurationOps, RoundTripDerivativesAreIdentity) {
  Graph graph;
  Tracer tracer(graph);
  const VecX<Sym> q0 = tracer.addInputs("q0", model.nq), d = tracer.addInputs("d", model.nv);
  const std::vector<NodeId> y =
      tracer.outputs(differenceConfiguration<Sym>(model, q0, integrateConfiguration<Sym>(model, q0, d)));
  const Jacobian jac = jacobian(graph, y, tracer.indices({"d"}));
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> weights(y.size());
  for (double& w : weights) w = u(rng);
  const Hessian hess = weightedHessian(graph, y, weights, tracer.indices({"d"}));
  const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(model.nv, model.nv);
  for (double angle : kAngles) {
    for (int trial = 0; trial < 3; ++trial) {
      const Eigen::VectorXd q0v = trial == 0 ? neutralConfiguration(model) : randomConfiguration(model, rng);
      const Eigen::VectorXd dv = randomTangent(model, rng, angle) * (angle == 0 ? 0.0 : 1.0);
      const std::vector<double> in = stack({q0v, dv});
      EXPECT_TRUE(close(evaluate(graph, y, in), dv, 1e-12));
      EXPECT_TRUE(close(evaluate(graph, jac, in), identity, angle < 0.1 ? 1e-12 : 1e-9)) << "|w| = " << angle;
      const Eigen::VectorXd h = evaluate(graph, hess.lower, in);
      EXPECT_TRUE(close(h, Eigen::VectorXd::Zero(h.size()), angle < 0.1 ? 1e-12 : 1e-8)) << "|w| = " << angle;
    }
  }
}

TEST_F(ConfigurationOps, IntegrateJacobiansMatchFiniteDifferences) {
  // q moved in the tangent space by e, then integrated by dq; and q in coordinates.
  Graph graph;
  Tracer tracer(graph);
  const VecX<Sym> q = tracer.addInputs("q", model.nq), e = tracer.addInputs("e", model.nv),
                  dq = tracer.addInputs("dq", model.nv);
  const VecX<Sym> moved = integrateConfiguration<Sym>(model, q, e);
  const std::vector<NodeId> y = tracer.outputs(integrateConfiguration<Sym>(model, moved, dq));
  const Jacobian by_e = jacobian(graph, y, tracer.indices({"e"}));
  const Jacobian by_dq = jacobian(graph, y, tracer.indices({"dq"}), JacobianMode::Forward);
  // Reverse mode multiplies the unselected branch's partials by 0: they must be finite.
  const Jacobian by_dq_reverse = jacobian(graph, y, tracer.indices({"dq"}), JacobianMode::Reverse);
  const Jacobian by_q = jacobian(graph, y, tracer.indices({"q"}));
  for (double angle : {0.0, 1e-9, 1e-4, 0.5, 3.0, 7.0}) {
    for (int trial = 0; trial < 3; ++trial) {
      const Eigen::VectorXd qv = trial == 0 ? neutralConfiguration(model) : randomConfiguration(model, rng);
      const Eigen::VectorXd dqv = randomTangent(model, rng, angle) * (angle == 0 ? 0.0 : 1.0);
      const std::vector<double> in = stack({qv, zero, dqv});
      const auto of_e = [&](const Eigen::VectorXd& x) { return integ(integ(qv, x), dqv); };
      const auto of_dq = [&](const Eigen::VectorXd& x) { return integ(qv, x); };
      const auto of_q = [&](const Eigen::VectorXd& x) { return integ(x, dqv); };
      EXPECT_TRUE(close(evaluate(graph, by_e, in), finiteDifferences(of_e, zero), 1e-8)) << "|w| = " << angle;
      EXPECT_TRUE(close(evaluate(graph, by_dq, in), finiteDifferences(of_dq, dqv), 1e-8)) << "|w| = " << angle;
      EXPECT_TRUE(close(evaluate(graph, by_dq_reverse, in), finiteDifferences(of_dq, dqv), 1e-8)) << "|w| = " << angle;
      EXPECT_TRUE(close(evaluate(graph, by_q, in), finiteDifferences(of_q, qv), 1e-8)) << "|w| = " << angle;
    }
  }
}

TEST_F(ConfigurationOps, DifferenceJacobiansMatchFiniteDifferences) {
  // difference(q0 (+) e0, q1 (+) e1) at e = 0: the tangent-space Jacobians; and the
  // Jacobian in the coordinates of q0 and q1.
  Graph graph;
  Tracer tracer(graph);
  const VecX<Sym> q0 = tracer.addInputs("q0", model.nq), q1 = tracer.addInputs("q1", model.nq),
                  e0 = tracer.addInputs("e0", model.nv), e1 = tracer.addInputs("e1", model.nv);
  const std::vector<NodeId> y = tracer.outputs(differenceConfiguration<Sym>(
      model, integrateConfiguration<Sym>(model, q0, e0), integrateConfiguration<Sym>(model, q1, e1)));
  const Jacobian by_e = jacobian(graph, y, tracer.indices({"e0", "e1"}), JacobianMode::Forward);
  const Jacobian by_e_reverse = jacobian(graph, y, tracer.indices({"e0", "e1"}), JacobianMode::Reverse);
  const Jacobian by_q = jacobian(graph, y, tracer.indices({"q0", "q1"}));
  const std::vector<NodeId> by_e_nodes = by_e.entries;
  const Jacobian second = jacobian(graph, by_e_nodes, tracer.indices({"e0", "e1"}));
  for (double angle : {0.0, 1e-12, 1e-9, 1e-4, 0.5, 2.0, 3.0}) {
    for (int trial = 0; trial < 3; ++trial) {
      const Eigen::VectorXd q0v = trial == 0 ? neutralConfiguration(model) : randomConfiguration(model, rng);
      const Eigen::VectorXd q1v = integ(q0v, randomTangent(model, rng, angle) * (angle == 0 ? 0.0 : 1.0));
      const std::vector<double> in = stack({q0v, q1v, zero, zero});
      Eigen::VectorXd e(2 * model.nv), q(2 * model.nq);
      e.setZero();
      q << q0v, q1v;
      const auto of_e = [&](const Eigen::VectorXd& x) {
        return diff(integ(q0v, x.head(model.nv)), integ(q1v, x.tail(model.nv)));
      };
      const auto of_q = [&](const Eigen::VectorXd& x) { return diff(x.head(model.nq), x.tail(model.nq)); };
      EXPECT_TRUE(close(evaluate(graph, by_e, in), finiteDifferences(of_e, e), 1e-8)) << "|w| = " << angle;
      EXPECT_TRUE(close(evaluate(graph, by_e_reverse, in), finiteDifferences(of_e, e), 1e-8)) << "|w| = " << angle;
      EXPECT_TRUE(close(evaluate(graph, by_q, in), finiteDifferences(of_q, q), 1e-8)) << "|w| = " << angle;
      // Second derivatives: the graph's Jacobian of its Jacobian against differences of it.
      const auto first = [&](const Eigen::VectorXd& x) {
        return evaluate(graph, by_e_nodes, stack({q0v, q1v, x.head(model.nv), x.tail(model.nv)}));
      };
      EXPECT_TRUE(close(evaluate(graph, second, in), finiteDifferences(first, e), 1e-7)) << "|w| = " << angle;
    }
  }
}

TEST_F(ConfigurationOps, IntegrateSecondDerivativesAtZeroMotion) {
  Graph graph;
  Tracer tracer(graph);
  const VecX<Sym> q = tracer.addInputs("q", model.nq), dq = tracer.addInputs("dq", model.nv);
  const std::vector<NodeId> y = tracer.outputs(integrateConfiguration<Sym>(model, q, dq));
  const Jacobian first = jacobian(graph, y, tracer.indices({"dq"}));
  const Jacobian second = jacobian(graph, first.entries, tracer.indices({"dq"}));
  for (int trial = 0; trial < 3; ++trial) {
    const Eigen::VectorXd qv = trial == 0 ? neutralConfiguration(model) : randomConfiguration(model, rng);
    const auto of_dq = [&](const Eigen::VectorXd& x) { return evaluate(graph, first.entries, stack({qv, x})); };
    EXPECT_TRUE(close(evaluate(graph, second, stack({qv, zero})), finiteDifferences(of_dq, zero), 1e-8));
  }
}

}  // namespace
}  // namespace robodiff::symbolic
