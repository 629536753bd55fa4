// solveWithIpopt on problems whose solutions are known independently: Hock & Schittkowski
// problem 71 (a nonconvex objective, an inequality and an equality constraint, bounds),
// checked by its published optimum and by the KKT conditions at the returned point; an
// unconstrained Rosenbrock function; cancellation from the iteration callback; a program
// error surfaces as the program's exception; a bad pattern is refused with its entry.
#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include "robodiff/batch/ipopt_solver.hpp"

namespace robodiff::testing {
namespace {

using batch::IpoptOptions;
using batch::SparsityEntries;

// min x0 x3 (x0 + x1 + x2) + x2  s.t.  x0 x1 x2 x3 >= 25,  sum xi^2 = 40,  1 <= x <= 5.
class Hs071 : public batch::NonlinearProgram {
 public:
  int variableCount() const override { return 4; }
  int constraintCount() const override { return 2; }
  void bounds(std::span<double> xl, std::span<double> xu, std::span<double> gl, std::span<double> gu) const override {
    std::fill(xl.begin(), xl.end(), 1.0);
    std::fill(xu.begin(), xu.end(), 5.0);
    gl[0] = 25;
    gu[0] = std::numeric_limits<double>::infinity();
    gl[1] = gu[1] = 40;
  }
  void startingPoint(std::span<double> x) const override {
    x[0] = 1, x[1] = 5, x[2] = 5, x[3] = 1;
  }
  double objective(std::span<const double> x) override { return x[0] * x[3] * (x[0] + x[1] + x[2]) + x[2]; }
  void gradient(std::span<const double> x, std::span<double> g) override {
    g[0] = x[3] * (2 * x[0] + x[1] + x[2]);
    g[1] = x[0] * x[3];
    g[2] = x[0] * x[3] + 1;
    g[3] = x[0] * (x[0] + x[1] + x[2]);
  }
  void constraints(std::span<const double> x, std::span<double> g) override {
    g[0] = x[0] * x[1] * x[2] * x[3];
    g[1] = x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3];
  }
  SparsityEntries constraintJacobianPattern() const override {
    SparsityEntries e;
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 4; ++c) e.emplace_back(r, c);
    return e;
  }
  void constraintJacobian(std::span<const double> x, std::span<double> v) override {
    v[0] = x[1] * x[2] * x[3], v[1] = x[0] * x[2] * x[3], v[2] = x[0] * x[1] * x[3], v[3] = x[0] * x[1] * x[2];
    for (int i = 0; i < 4; ++i) v[4 + i] = 2 * x[i];
  }
  SparsityEntries hessianPattern() const override {
    SparsityEntries e;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c <= r; ++c) e.emplace_back(r, c);
    return e;
  }
  // Full lower triangle, row by row: (0,0) (1,0) (1,1) (2,0) (2,1) (2,2) (3,0) ... (3,3).
  void hessian(std::span<const double> x, double s, std::span<const double> l, std::span<double> v) override {
    double h[4][4] = {};
    h[0][0] = s * 2 * x[3];
    h[1][0] = s * x[3];
    h[2][0] = s * x[3];
    h[3][0] = s * (2 * x[0] + x[1] + x[2]);
    h[3][1] = s * x[0];
    h[3][2] = s * x[0];
    h[1][0] += l[0] * x[2] * x[3];
    h[2][0] += l[0] * x[1] * x[3];
    h[2][1] += l[0] * x[0] * x[3];
    h[3][0] += l[0] * x[1] * x[2];
    h[3][1] += l[0] * x[0] * x[2];
    h[3][2] += l[0] * x[0] * x[1];
    for (int i = 0; i < 4; ++i) h[i][i] += l[1] * 2;
    int k = 0;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c <= r; ++c) v[k++] = h[r][c];
  }
  bool iterationDone(const batch::IterationInfo& info) override {
    ++iterations_seen;
    return stop_after < 0 || info.iteration < stop_after;
  }
  int iterations_seen = 0;
  int stop_after = -1;
};

TEST(IpoptSolver, SolvesHs071ToItsKnownOptimumWithKktConditions) {
  Hs071 problem;
  IpoptOptions options;
  options.derivative_test = "second-order";  // Ipopt's own check of the hand derivatives (silent at print_level 0)
  const batch::IpoptResult r = batch::solveWithIpopt(problem, options);
  ASSERT_TRUE(r.success) << r.status;
  EXPECT_EQ(r.status, "Solve_Succeeded");
  EXPECT_GT(r.iterations, 0);
  EXPECT_EQ(problem.iterations_seen, r.iterations + 1);  // iteration 0 is reported too
  // Hock & Schittkowski (1981), problem 71: f* = 17.0140173 at (1, 4.7429994, 3.8211503, 1.3794082).
  EXPECT_NEAR(r.objective, 17.0140173, 1e-6);
  EXPECT_NEAR(r.x[0], 1.0, 1e-6);
  EXPECT_NEAR(r.x[1], 4.7429994, 1e-5);
  EXPECT_NEAR(r.x[2], 3.8211503, 1e-5);
  EXPECT_NEAR(r.x[3], 1.3794082, 1e-5);
  EXPECT_LT(r.constraint_violation, 1e-6);  // sum x^2 = 40 to ~1e-8 relative
  // Stationarity in the free variables x1..x3 (x0 sits on its bound): grad f + J^T lambda = 0
  // (Ipopt's sign convention for lambda).
  double grad[4], jac[8];
  problem.gradient(r.x, grad);
  problem.constraintJacobian(r.x, jac);
  for (int i = 1; i < 4; ++i)
    EXPECT_NEAR(grad[i] + r.multipliers[0] * jac[i] + r.multipliers[1] * jac[4 + i], 0.0, 1e-6) << "x" << i;
}

TEST(IpoptSolver, CancelledFromTheIterationCallback) {
  Hs071 problem;
  problem.stop_after = 2;
  const batch::IpoptResult r = batch::solveWithIpopt(problem);
  EXPECT_TRUE(r.cancelled);
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.status, "User_Requested_Stop");
}

class Rosenbrock : public Hs071 {
 public:
  int variableCount() const override { return 2; }
  int constraintCount() const override { return 0; }
  void bounds(std::span<double> xl, std::span<double> xu, std::span<double>, std::span<double>) const override {
    std::fill(xl.begin(), xl.end(), -std::numeric_limits<double>::infinity());
    std::fill(xu.begin(), xu.end(), std::numeric_limits<double>::infinity());
  }
  void startingPoint(std::span<double> x) const override { x[0] = -1.2, x[1] = 1; }
  double objective(std::span<const double> x) override {
    if (throw_at_objective) throw std::runtime_error("the program failed on purpose");
    return 100 * std::pow(x[1] - x[0] * x[0], 2) + std::pow(1 - x[0], 2);
  }
  void gradient(std::span<const double> x, std::span<double> g) override {
    g[0] = -400 * x[0] * (x[1] - x[0] * x[0]) - 2 * (1 - x[0]);
    g[1] = 200 * (x[1] - x[0] * x[0]);
  }
  void constraints(std::span<const double>, std::span<double>) override {}
  SparsityEntries constraintJacobianPattern() const override { return {}; }
  void constraintJacobian(std::span<const double>, std::span<double>) override {}
  SparsityEntries hessianPattern() const override { return {{0, 0}, {1, 0}, {1, 1}}; }
  void hessian(std::span<const double> x, double s, std::span<const double>, std::span<double> v) override {
    v[0] = s * (1200 * x[0] * x[0] - 400 * x[1] + 2);
    v[1] = s * (-400 * x[0]);
    v[2] = s * 200;
  }
  bool throw_at_objective = false;
};

TEST(IpoptSolver, UnconstrainedRosenbrockReachesItsMinimum) {
  Rosenbrock problem;
  const batch::IpoptResult r = batch::solveWithIpopt(problem);
  ASSERT_TRUE(r.success) << r.status;
  EXPECT_NEAR(r.x[0], 1.0, 1e-7);
  EXPECT_NEAR(r.x[1], 1.0, 1e-7);
}

TEST(IpoptSolver, AProgramErrorIsRethrown) {
  Rosenbrock problem;
  problem.throw_at_objective = true;
  try {
    batch::solveWithIpopt(problem);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "the program failed on purpose");
  }
}

class UpperTriangle : public Rosenbrock {
 public:
  SparsityEntries hessianPattern() const override { return {{0, 0}, {0, 1}, {1, 1}}; }
};

TEST(IpoptSolver, AnUpperTriangleHessianPatternIsRefused) {
  UpperTriangle problem;
  try {
    batch::solveWithIpopt(problem);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("(0, 1) is above the diagonal"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace robodiff::testing
