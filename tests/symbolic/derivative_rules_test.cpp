// The derivative of every Op, in forward and reverse mode, against central finite
// differences of Graph::evaluate; and its second derivatives (the Hessian, which
// differentiates the derivative rules' own nodes) against differences of the gradient.
#include <cmath>
#include <functional>

#include <gtest/gtest.h>

#include "robodiff/symbolic/differentiation.hpp"
#include "robodiff/symbolic/hessian.hpp"
#include "robodiff/symbolic/sym.hpp"

namespace robodiff::symbolic {
namespace {

struct OpCase {
  std::string name;
  std::function<Sym(const Sym&, const Sym&, const Sym&)> f;  // of three inputs
  std::vector<double> x;                                   // a point inside the domain
};

// Arguments are small expressions of the inputs, so the chain rule is exercised too.
std::vector<OpCase> opCases() {
  auto inner = [](const Sym& a, const Sym& b) { return 0.5 * a + 0.25 * b * b; };
  return {
      {"neg", [](auto& a, auto& b, auto&) { return -(a * b); }, {0.3, -0.7, 0}},
      {"add", [](auto& a, auto& b, auto&) { return a * a + b; }, {0.3, -0.7, 0}},
      {"sub", [](auto& a, auto& b, auto&) { return a - b * a; }, {0.3, -0.7, 0}},
      {"mul", [](auto& a, auto& b, auto& c) { return a * b * c; }, {0.3, -0.7, 1.3}},
      {"div", [](auto& a, auto& b, auto& c) { return (a + c) / (b * c); }, {0.3, -0.7, 1.3}},
      {"sin", [&](auto& a, auto& b, auto&) { return sin(inner(a, b)); }, {0.3, -0.7, 0}},
      {"cos", [&](auto& a, auto& b, auto&) { return cos(inner(a, b)); }, {0.3, -0.7, 0}},
      {"tan", [&](auto& a, auto& b, auto&) { return tan(inner(a, b)); }, {0.3, -0.7, 0}},
      {"asin", [&](auto& a, auto& b, auto&) { return asin(inner(a, b)); }, {0.3, -0.7, 0}},
      {"acos", [&](auto& a, auto& b, auto&) { return acos(inner(a, b)); }, {0.3, -0.7, 0}},
      {"atan", [&](auto& a, auto& b, auto&) { return atan(inner(a, b)); }, {0.3, -0.7, 0}},
      {"exp", [&](auto& a, auto& b, auto&) { return exp(inner(a, b)); }, {0.3, -0.7, 0}},
      {"log", [&](auto& a, auto& b, auto&) { return log(inner(a, b)); }, {0.3, -0.7, 0}},
      {"sqrt", [&](auto& a, auto& b, auto&) { return sqrt(inner(a, b)); }, {0.3, -0.7, 0}},
      {"tanh", [&](auto& a, auto& b, auto&) { return tanh(inner(a, b)); }, {0.3, -0.7, 0}},
      {"abs_positive", [](auto& a, auto& b, auto&) { return abs(a * b + 1.0); }, {0.3, -0.7, 0}},
      {"abs_negative", [](auto& a, auto& b, auto&) { return abs(a * b - 1.0); }, {0.3, -0.7, 0}},
      {"atan2", [](auto& a, auto& b, auto& c) { return atan2(a * c, b + c); }, {0.3, -0.7, 1.3}},
      {"atan2_left_half", [](auto& a, auto& b, auto& c) { return atan2(a * c, b - c); }, {0.3, -0.7, 1.3}},
      {"pow_both", [](auto& a, auto& b, auto& c) { return pow(c * c, a + b); }, {0.3, -0.7, 1.3}},
      {"pow_constant_exponent", [](auto& a, auto&, auto& c) { return pow(a + c, 3.5); }, {0.3, -0.7, 1.3}},
      {"pow_constant_base", [](auto& a, auto& b, auto&) { return pow(2.5, a * b); }, {0.3, -0.7, 1.3}},
      {"min_first", [](auto& a, auto& b, auto&) { return min(a * b, b); }, {0.3, -0.7, 0}},
      {"min_second", [](auto& a, auto& b, auto&) { return min(a * b, a); }, {0.3, -0.7, 0}},
      {"max_first", [](auto& a, auto& b, auto&) { return max(a * b, b); }, {0.3, -0.7, 0}},
      {"max_second", [](auto& a, auto& b, auto&) { return max(a * b, a); }, {0.3, -0.7, 0}},
      {"select_positive", [](auto& a, auto& b, auto& c) { return selectPositive(a, b * c, a * c); }, {0.3, -0.7, 1.3}},
      {"select_negative", [](auto& a, auto& b, auto& c) { return selectPositive(b, b * c, a * c); }, {0.3, -0.7, 1.3}},
  };
}

class OpDerivative : public ::testing::TestWithParam<OpCase> {
 protected:
  void SetUp() override {
    x = Sym(g, g.input(0));
    y = Sym(g, g.input(1));
    z = Sym(g, g.input(2));
    f = GetParam().f(x, y, z).nodeIn(g);
  }
  // Central differences of the nodes `out` at the case's point, one column per input.
  Eigen::MatrixXd finiteDifferences(const std::vector<NodeId>& out, double h = 1e-6) {
    Eigen::MatrixXd d(out.size(), 3);
    for (int j = 0; j < 3; ++j) {
      std::vector<double> xp = GetParam().x, xm = GetParam().x;
      xp[j] += h;
      xm[j] -= h;
      const std::vector<double> fp = g.evaluate(out, xp), fm = g.evaluate(out, xm);
      for (std::size_t i = 0; i < out.size(); ++i) d(i, j) = (fp[i] - fm[i]) / (2 * h);
    }
    return d;
  }
  Eigen::MatrixXd values(int rows, int cols, const std::vector<NodeId>& nodes) {
    const std::vector<double> v = g.evaluate(nodes, GetParam().x);
    return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(v.data(), rows, cols);
  }

  Graph g;
  Sym x, y, z;
  NodeId f = 0;
  const std::vector<std::uint32_t> wrt = {0, 1, 2};
};

TEST_P(OpDerivative, FirstDerivativeMatchesFiniteDifferences) {
  const Eigen::MatrixXd fd = finiteDifferences({f});
  for (JacobianMode mode : {JacobianMode::Forward, JacobianMode::Reverse}) {
    SCOPED_TRACE(toString(mode));
    const Jacobian jac = jacobian(g, {f}, wrt, mode);
    EXPECT_EQ(jac.mode, mode);
    const Eigen::MatrixXd d = values(1, 3, jac.entries);
    EXPECT_LT((d - fd).cwiseAbs().maxCoeff(), 1e-7 * std::max(1.0, fd.cwiseAbs().maxCoeff())) << d << "\nvs\n" << fd;
  }
  const std::vector<NodeId> grad = gradient(g, f, wrt);
  EXPECT_LT((values(1, 3, grad) - fd).cwiseAbs().maxCoeff(), 1e-7 * std::max(1.0, fd.cwiseAbs().maxCoeff()));
}

TEST_P(OpDerivative, SecondDerivativeMatchesDifferencesOfTheGradient) {
  const std::vector<NodeId> grad = gradient(g, f, wrt);
  const Eigen::MatrixXd fd = finiteDifferences(grad, 1e-5);
  for (JacobianMode mode : {JacobianMode::Forward, JacobianMode::Reverse, JacobianMode::Automatic}) {
    SCOPED_TRACE(toString(mode));
    const Hessian h = hessian(g, f, wrt, mode);
    Eigen::MatrixXd d(3, 3);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) d(i, j) = g.evaluate({h(i, j)}, GetParam().x)[0];
    EXPECT_LT((d - fd).cwiseAbs().maxCoeff(), 1e-6 * std::max(1.0, fd.cwiseAbs().maxCoeff())) << d << "\nvs\n" << fd;
  }
}

INSTANTIATE_TEST_SUITE_P(EveryOp, OpDerivative, ::testing::ValuesIn(opCases()),
                         [](const auto& info) { return info.param.name; });

TEST(Differentiation, SelectIsBranchFreeInTheDerivative) {
  // The derivative of min/max/abs at a point chooses with selectPositive nodes, so one
  // derivative graph is right on both sides of the switch.
  Graph g;
  const Sym x(g, g.input(0)), y(g, g.input(1));
  const NodeId f = (max(x, y) + abs(x) * 3.0).nodeIn(g);
  const Jacobian jac = jacobian(g, {f}, {0, 1});
  EXPECT_EQ(g.evaluate(jac.entries, {2.0, 1.0}), (std::vector<double>{4.0, 0.0}));
  EXPECT_EQ(g.evaluate(jac.entries, {-2.0, 1.0}), (std::vector<double>{-3.0, 1.0}));
}

TEST(Differentiation, InputsOutsideTheGraphAndConstantOutputsGiveZeros) {
  Graph g;
  const Sym x(g, g.input(0));
  const NodeId f = (x * x).nodeIn(g);
  for (JacobianMode mode : {JacobianMode::Forward, JacobianMode::Reverse}) {
    const Jacobian jac = jacobian(g, {f, g.constant(3.0), g.input(0)}, {7, 0}, mode);
    EXPECT_EQ(jac(0, 0), g.zero());
    EXPECT_EQ(jac(1, 1), g.zero());
    EXPECT_EQ(jac(2, 1), g.one());
    EXPECT_EQ(g.evaluate({jac(0, 1)}, {1.5})[0], 3.0);
  }
}

TEST(Differentiation, DirectionalDerivativeIsJacobianTimesDirection) {
  Graph g;
  const Sym x(g, g.input(0)), y(g, g.input(1));
  const std::vector<NodeId> f = {(sin(x) * y).nodeIn(g), (x / y).nodeIn(g)};
  const NodeId d0 = g.input(2), d1 = g.input(3);  // the direction as inputs
  const std::vector<NodeId> jv = directionalDerivative(g, f, {0, 1}, {d0, d1});
  const Jacobian jac = jacobian(g, f, {0, 1});
  const std::vector<double> at = {0.4, 1.7, -0.3, 2.0};
  const std::vector<double> j = g.evaluate(jac.entries, at), v = g.evaluate(jv, at);
  EXPECT_NEAR(v[0], j[0] * at[2] + j[1] * at[3], 1e-14);
  EXPECT_NEAR(v[1], j[2] * at[2] + j[3] * at[3], 1e-14);
}

TEST(Differentiation, AutomaticModeTakesFewerSweeps) {
  Graph g;
  const Sym x(g, g.input(0)), y(g, g.input(1)), z(g, g.input(2));
  const NodeId f = (x * y * z).nodeIn(g), h = (x + y).nodeIn(g);
  EXPECT_EQ(jacobian(g, {f}, {0, 1, 2}).mode, JacobianMode::Reverse);     // 1 row, 3 columns
  EXPECT_EQ(jacobian(g, {f, h, x.node()}, {0}).mode, JacobianMode::Forward);  // 3 rows, 1 column
  // At a tie both modes are built, and only the smaller result's nodes stay.
  const NodeId s = (sin(x) * exp(y)).nodeIn(g), c = (cos(x) / y).nodeIn(g);
  Graph forward_only = g, reverse_only = g;
  const std::size_t before = g.size();
  const Jacobian fwd = jacobian(forward_only, {s, c}, {0, 1}, JacobianMode::Forward);
  const Jacobian rev = jacobian(reverse_only, {s, c}, {0, 1}, JacobianMode::Reverse);
  const Jacobian square = jacobian(g, {s, c}, {0, 1});
  EXPECT_EQ(g.size(), std::min(forward_only.size(), reverse_only.size()));
  EXPECT_GT(g.size(), before);
  EXPECT_EQ(square.entries, square.mode == JacobianMode::Forward ? fwd.entries : rev.entries);
  EXPECT_EQ(jacobian(g, {s, c}, {0, 1}, JacobianMode::Smallest).entries, square.entries);
}

}  // namespace
}  // namespace robodiff::symbolic
