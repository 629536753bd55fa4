#pragma once
// A smooth nonlinear program, as robodiff's batch work poses it to a solver:
//
//   minimise f(x)  subject to  g_lower <= g(x) <= g_upper,  x_lower <= x <= x_upper
//
// with exact first and second derivatives (from generated code). Sparse matrices are
// given as a fixed pattern of (row, col) entries, asked for once, then values in that
// order at each call. The Hessian is that of the Lagrangian
//   sigma * f(x) + sum_i lambda_i g_i(x),
// lower triangle only (row >= col), as Ipopt wants it.
//
// No solver types here: ipopt_solver.hpp adapts this to Ipopt; tests can drive a
// program directly.

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace robodiff::batch {

using SparsityEntries = std::vector<std::pair<int, int>>;  // (row, col), 0-based

// What the solver reports after each iteration.
struct IterationInfo {
  int iteration = 0;
  double objective = 0;
  double primal_infeasibility = 0;  // max constraint violation
  double dual_infeasibility = 0;
  double barrier = 0;               // log10(mu)
};

class NonlinearProgram {
 public:
  virtual ~NonlinearProgram() = default;

  virtual int variableCount() const = 0;
  virtual int constraintCount() const = 0;
  // Bounds: +-infinity (std::numeric_limits<double>::infinity()) for none.
  virtual void bounds(std::span<double> x_lower, std::span<double> x_upper, std::span<double> g_lower,
                      std::span<double> g_upper) const = 0;
  virtual void startingPoint(std::span<double> x) const = 0;

  // The evaluations. `x` is the same pointer and values until a call with new values;
  // programs may cache what several evaluations at one x share.
  virtual double objective(std::span<const double> x) = 0;
  virtual void gradient(std::span<const double> x, std::span<double> gradient) = 0;
  virtual void constraints(std::span<const double> x, std::span<double> g) = 0;
  virtual SparsityEntries constraintJacobianPattern() const = 0;
  virtual void constraintJacobian(std::span<const double> x, std::span<double> values) = 0;
  virtual SparsityEntries hessianPattern() const = 0;  // lower triangle
  virtual void hessian(std::span<const double> x, double objective_factor, std::span<const double> multipliers,
                       std::span<double> values) = 0;

  // After each iteration; false stops the solver (cancelled).
  virtual bool iterationDone(const IterationInfo& info) { return true; }
};

}  // namespace robodiff::batch
