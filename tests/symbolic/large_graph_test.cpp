// Graphs of a million nodes: building, differentiating in both modes and evaluating are
// loops over node ids, so nothing overflows the stack and the time stays linear.
#include <chrono>
#include <cmath>

#include <gtest/gtest.h>

#include "robodiff/symbolic/differentiation.hpp"
#include "robodiff/symbolic/sym.hpp"

namespace robodiff::symbolic {
namespace {

TEST(LargeGraph, MillionNodeChainDifferentiatesInBothModes) {
  const auto start = std::chrono::steady_clock::now();
  // x_{k+1} = x_k + h sin(x_k) y: four nodes a step, each depending on the previous.
  constexpr int kSteps = 260'000;
  constexpr double h = 1e-5;
  Graph g;
  const Sym x0(g, g.input(0)), y(g, g.input(1));
  Sym x = x0;
  for (int k = 0; k < kSteps; ++k) x = x + h * (sin(x) * y);
  const NodeId f = x.node();
  ASSERT_GE(g.size(), 1'000'000u);

  // The reference: the same recursion with its derivatives, in double.
  const double X0 = 0.3, Y = 2.0;
  double xv = X0, dx_dx0 = 1, dx_dy = 0;
  for (int k = 0; k < kSteps; ++k) {
    const double s = std::sin(xv), c = std::cos(xv);
    dx_dx0 = dx_dx0 + h * (c * dx_dx0 * Y);
    dx_dy = dx_dy + h * (c * dx_dy * Y + s);
    xv = xv + h * (s * Y);
  }

  const std::size_t value_nodes = g.size();
  const Jacobian rev = jacobian(g, {f}, {0, 1}, JacobianMode::Reverse);
  const std::size_t after_reverse = g.size();
  const Jacobian fwd = jacobian(g, {f}, {0, 1}, JacobianMode::Forward);
  const std::vector<double> r = g.evaluate({f, rev(0, 0), rev(0, 1), fwd(0, 0), fwd(0, 1)}, {X0, Y});
  EXPECT_NEAR(r[0], xv, 1e-12 * std::abs(xv));
  for (int k : {1, 3}) EXPECT_NEAR(r[k], dx_dx0, 1e-9 * std::abs(dx_dx0));
  for (int k : {2, 4}) EXPECT_NEAR(r[k], dx_dy, 1e-9 * std::abs(dx_dy));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "chain: " << value_nodes << " nodes; reverse Jacobian +" << after_reverse - value_nodes
            << ", forward Jacobian +" << g.size() - after_reverse << " nodes; " << seconds << " s in all\n";
  EXPECT_LT(seconds, 60.0);
}

}  // namespace
}  // namespace robodiff::symbolic
