// Symbolic Jacobians of traced dynamics: RNEA w.r.t. [q, v, a] and ABA w.r.t.
// [q, v, tau], against central differences of the double algorithms (generated robots,
// prismatic joints and a floating base included) and against Pinocchio's derivatives in
// ../shared/golden; forward and reverse mode against each other; the sparsity pattern.
//
// The q-derivative is taken in the tangent space, as the golden files do: the function
// is traced at q = q0 (+) dq (integrateSecondOrder) and differentiated w.r.t. dq at
// dq = 0; for a fixed base this is the ordinary partial derivative.
#include <memory>
#include <random>

#include <gtest/gtest.h>

#include "robodiff/dynamics/all.hpp"
#include "robodiff/model/robot_generator.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "robodiff/symbolic/configuration.hpp"
#include "robodiff/symbolic/differentiation.hpp"
#include "robodiff/symbolic/tracer.hpp"
#include "support/robot_cases.hpp"
#include "support/golden.hpp"
#include "support/test_paths.hpp"

namespace robodiff::symbolic {
namespace {

using testing::matricesAgree;

enum class Function { Rnea, Aba };  // f(q, v, a) = tau, or f(q, v, tau) = ddq

// f traced at q0 (+) dq: inputs [q0, dq, v, x] (x = a or tau), outputs f, and its
// Jacobian w.r.t. [dq, v, x].
struct TangentTrace {
  Graph graph;
  std::vector<NodeId> value;
  Jacobian jac;
};

std::unique_ptr<TangentTrace> traceTangent(const Model& model, Function fn, JacobianMode mode = JacobianMode::Automatic) {
  auto t = std::make_unique<TangentTrace>();
  Tracer tracer(t->graph);
  const VecX<Sym> q0 = tracer.addInputs("q0", model.nq), dq = tracer.addInputs("dq", model.nv);
  const VecX<Sym> v = tracer.addInputs("v", model.nv), x = tracer.addInputs("x", model.nv);
  const VecX<Sym> q = integrateSecondOrder(model, q0, dq);
  Data<Sym> data(model);
  t->value = tracer.outputs(fn == Function::Rnea ? rnea(model, data, q, v, x) : aba(model, data, q, v, x));
  t->jac = jacobian(t->graph, t->value, tracer.indices({"dq", "v", "x"}), mode);
  return t;
}

// The inputs [q0 = q, dq = 0, v, x].
std::vector<double> inputsAt(const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& x) {
  std::vector<double> in(q.data(), q.data() + q.size());
  in.resize(in.size() + v.size(), 0.0);
  in.insert(in.end(), v.data(), v.data() + v.size());
  in.insert(in.end(), x.data(), x.data() + x.size());
  return in;
}

// The Jacobian's value at (q, v, x), dq = 0.
Eigen::MatrixXd jacobianAt(const TangentTrace& t, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                           const Eigen::VectorXd& x) {
  const std::vector<double> out = t.graph.evaluate(t.jac.entries, inputsAt(q, v, x));
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(out.data(), t.jac.rows,
                                                                                                    t.jac.cols);
}

// Central differences of the double algorithm: q moved by integrate in the tangent space.
// The step keeps their rounding (one ulp of a torque of ~10, 1.8e-15, over 2h: 9e-11)
// well under matricesAgree's 1e-6 of its floor (1e-3 of the largest entry); at 1e-6 a
// single ulp reached 1.4e-8 against a limit of 1.2e-8. Truncation, ~h^2 f''' / 6, is
// below 1e-10 of the entries.
Eigen::MatrixXd derivativeFiniteDifferences(const Model& model, Function fn, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                  const Eigen::VectorXd& x, double h = 1e-5) {
  Data<double> data(model);
  auto f = [&](const Eigen::VectorXd& qq, const Eigen::VectorXd& vv, const Eigen::VectorXd& xx) -> Eigen::VectorXd {
    return fn == Function::Rnea ? rnea(model, data, qq, vv, xx) : aba(model, data, qq, vv, xx);
  };
  const int n = model.nv;
  Eigen::MatrixXd d(n, 3 * n);
  for (int j = 0; j < n; ++j) {
    const Eigen::VectorXd e = Eigen::VectorXd::Unit(n, j) * h;
    d.col(j) = (f(integrate(model, q, e), v, x) - f(integrate(model, q, -e), v, x)) / (2 * h);
    d.col(n + j) = (f(q, v + e, x) - f(q, v - e, x)) / (2 * h);
    d.col(2 * n + j) = (f(q, v, x + e) - f(q, v, x - e)) / (2 * h);
  }
  return d;
}

using testing::RobotCase;

std::vector<RobotCase> robotCases() {
  GeneratorOptions quadruped;
  quadruped.kind = RobotKind::Tree;
  quadruped.tree = "quadruped";
  quadruped.seed = 5;
  quadruped.prismatic_fraction = 0.25;
  GeneratorOptions chain;
  chain.joints = 7;
  chain.seed = 13;
  chain.prismatic_fraction = 0.3;
  return {{"quadruped_free_flyer", quadruped, RootJoint::FreeFlyer},
          {"quadruped_fixed", quadruped, RootJoint::Fixed},
          {"chain7_prismatic", chain, RootJoint::Fixed}};
}

class DynamicsDerivatives : public ::testing::TestWithParam<RobotCase> {
 protected:
  void SetUp() override {
    model = GetParam().load();
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1, 1);
    q = randomConfiguration(model, rng);
    v = Eigen::VectorXd::NullaryExpr(model.nv, [&] { return u(rng); });
    a = Eigen::VectorXd::NullaryExpr(model.nv, [&] { return u(rng); });
    tau = Eigen::VectorXd::NullaryExpr(model.nv, [&] { return 5 * u(rng); });
  }
  Model model;
  Eigen::VectorXd q, v, a, tau;
};

TEST_P(DynamicsDerivatives, RneaJacobianMatchesFiniteDifferences) {
  const auto t = traceTangent(model, Function::Rnea);
  EXPECT_EQ(t->jac.mode, JacobianMode::Reverse);  // nv rows, 3 nv columns
  EXPECT_TRUE(matricesAgree(jacobianAt(*t, q, v, a), derivativeFiniteDifferences(model, Function::Rnea, q, v, a), 1e-6));
  // d tau / d a = M.
  Data<double> data(model);
  EXPECT_TRUE(matricesAgree(jacobianAt(*t, q, v, a).rightCols(model.nv), crba(model, data, q), 1e-12));
}

TEST_P(DynamicsDerivatives, AbaJacobianMatchesFiniteDifferences) {
  const auto t = traceTangent(model, Function::Aba);
  EXPECT_TRUE(matricesAgree(jacobianAt(*t, q, v, tau), derivativeFiniteDifferences(model, Function::Aba, q, v, tau), 1e-6));
}

TEST_P(DynamicsDerivatives, ForwardAndReverseModeAgree) {
  for (Function fn : {Function::Rnea, Function::Aba}) {
    SCOPED_TRACE(fn == Function::Rnea ? "rnea" : "aba");
    const auto fwd = traceTangent(model, fn, JacobianMode::Forward);
    const auto rev = traceTangent(model, fn, JacobianMode::Reverse);
    const Eigen::VectorXd& x = fn == Function::Rnea ? a : tau;
    // The two modes sum the same products in other orders: they differ by rounding, which
    // reaches ~4e-14 on entries near 0 (quadruped ABA), ~1e-15 of the largest entry;
    // matricesAgree measures it against 1e-3 of that, so 1e-11 here is ~1e-14 of it.
    EXPECT_TRUE(matricesAgree(jacobianAt(*fwd, q, v, x), jacobianAt(*rev, q, v, x), 1e-11));
    EXPECT_EQ(fwd->jac.pattern(), rev->jac.pattern());
  }
}

TEST_P(DynamicsDerivatives, SparsityPatternIsTheStructuralNonzeros) {
  const auto t = traceTangent(model, Function::Rnea);
  const SparsityPattern p = t->jac.pattern();
  ASSERT_EQ(p.rows, model.nv);
  ASSERT_EQ(p.cols, 3 * model.nv);
  ASSERT_EQ(static_cast<int>(p.row_ptr.size()), model.nv + 1);
  // The sparse values are the dense entries at the pattern's positions.
  const Eigen::MatrixXd dense = jacobianAt(*t, q, v, a);
  const std::vector<double> nz = t->graph.evaluate(t->jac.nonzeros(), inputsAt(q, v, a));
  ASSERT_EQ(static_cast<int>(nz.size()), p.nnz());
  for (int r = 0, k = 0; r < p.rows; ++r)
    for (int i = p.row_ptr[r]; i < p.row_ptr[r + 1]; ++i, ++k) EXPECT_EQ(nz[k], dense(r, p.col_idx[i]));
  // Every entry outside the pattern is a structural zero: exactly zero in the finite
  // differences too; the pattern lies within the dependency pattern.
  const Eigen::MatrixXd fd = derivativeFiniteDifferences(model, Function::Rnea, q, v, a);
  const SparsityPattern dep = dependencyPattern(t->graph, t->value, [&] {
    std::vector<std::uint32_t> wrt;
    for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(3 * model.nv); ++i) wrt.push_back(model.nq + i);
    return wrt;
  }());
  for (int r = 0; r < p.rows; ++r)
    for (int c = 0; c < p.cols; ++c) {
      if (p.contains(r, c)) {
        EXPECT_TRUE(dep.contains(r, c)) << r << ", " << c;
      } else {
        EXPECT_EQ(fd(r, c), 0.0) << r << ", " << c;
      }
    }
  // Branches of a tree do not interact: with a fixed base, d tau_i / d a_j (= M) is
  // nonzero exactly when one joint supports the other.
  if (model.root == RootJoint::Fixed) {
    for (int i = 0; i < model.njoints(); ++i)
      for (int j = 0; j < model.njoints(); ++j)
        EXPECT_EQ(p.contains(i, 2 * model.nv + j), model.supports(i, j) || model.supports(j, i)) << i << ", " << j;
    if (GetParam().options.kind == RobotKind::Tree) {
      EXPECT_LT(p.nnz(), 3 * model.nv * model.nv);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Robots, DynamicsDerivatives, ::testing::ValuesIn(robotCases()),
                         [](const auto& info) { return info.param.label; });

// Against Pinocchio's computeRNEADerivatives / computeABADerivatives, every sample.
class GoldenDerivatives : public ::testing::TestWithParam<std::string> {};

TEST_P(GoldenDerivatives, RneaAndAba) {
  ROBODIFF_REQUIRE_SHARED(shared);
  const testing::GoldenRobot golden = testing::loadGolden(shared, GetParam());
  const Model model = loadUrdfFile(golden.urdf.string(), golden.free_flyer ? RootJoint::FreeFlyer : RootJoint::Fixed);
  const int n = model.nv;
  const auto rnea_trace = traceTangent(model, Function::Rnea);
  const auto aba_trace = traceTangent(model, Function::Aba);
  for (std::size_t s = 0; s < golden.samples.size(); ++s) {
    SCOPED_TRACE("sample " + std::to_string(s));
    const auto& g = golden.samples[s];
    const Eigen::MatrixXd dtau = jacobianAt(*rnea_trace, g.q, g.v, g.a);
    EXPECT_TRUE(matricesAgree(dtau.leftCols(n), g.dtau_dq));
    EXPECT_TRUE(matricesAgree(dtau.middleCols(n, n), g.dtau_dv));
    EXPECT_TRUE(matricesAgree(dtau.rightCols(n), g.M));
    const Eigen::MatrixXd dddq = jacobianAt(*aba_trace, g.q, g.v, g.tau);
    EXPECT_TRUE(matricesAgree(dddq.leftCols(n), g.dddq_dq));
    EXPECT_TRUE(matricesAgree(dddq.middleCols(n, n), g.dddq_dv));
    EXPECT_TRUE(matricesAgree(dddq.rightCols(n), g.M.inverse()));
  }
}

INSTANTIATE_TEST_SUITE_P(Shared, GoldenDerivatives, ::testing::ValuesIn(testing::goldenNames()),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace robodiff::symbolic
