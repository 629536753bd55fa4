#pragma once
// The trajectory optimisation problem of trajectory_optimization.hpp as a
// NonlinearProgram, with exact derivatives.
//
// Each knot's z_k = (q_k, v_k, a_k) is linear in at most three knots' positions,
// z_k = sum_j S_kj q_j with S_kj = [cq I; cv I; ca I] (the finite-difference stencil), so
// with tau_k = RNEA(z_k), J_k = d tau_k / dz and c_k the quadrature weight:
//   gradient   d/dq_j = sum_k S_kj^T (2 w c_k J_k^T tau_k + 2 s c_k [0; 0; a_k])
//   Hessian    d2/dq_i dq_j = sum_k S_ki^T K_k S_kj,
//              K_k = sigma (2 w c_k J_k^T J_k + 2 s c_k [0 0 0; 0 0 0; 0 0 I])
//                    + sum_r mu_kr d2 tau_kr / dz^2,   mu_k = sigma 2 w c_k tau_k + lambda_k
// (lambda_k: the multipliers of knot k's torque constraints), the last term from the
// second-order function with mu_k as its weights, all knots in one batch.
// Knots at most two apart share a stencil, so the Hessian is banded: blocks (i, j) with
// |i - j| <= 2, dense nv x nv when the dynamics enter (w > 0 or torque limits), diagonal
// otherwise; only the lower triangle is listed.
// Constraints: the velocity rows (interior knot, joint with a finite limit), then the
// torque rows (knot, joint with a finite effort limit) when torque limits are on.
//
// Evaluations at one x are cached: Ipopt asks f, grad f, g and its Jacobian at the same
// point, all from one batch of first-order evaluations. One program serves one solve at
// a time (the cache is not shared between threads).

#include <memory>
#include <span>
#include <vector>

#include "robodiff/batch/nonlinear_program.hpp"
#include "robodiff/batch/trajectory_optimization.hpp"
#include "robodiff/batch/trajectory_optimization_functions.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::batch {

class TrajectoryProgram final : public NonlinearProgram {
 public:
  // Checks the options (checkTrajectoryOptions); `functions` must be opened for `model`.
  TrajectoryProgram(const Model& model, const TrajectoryFunctions& functions,
                    const TrajectoryOptimizationOptions& options);
  ~TrajectoryProgram() override;
  TrajectoryProgram(const TrajectoryProgram&) = delete;
  TrajectoryProgram& operator=(const TrajectoryProgram&) = delete;

  int variableCount() const override;
  int constraintCount() const override;
  void bounds(std::span<double> x_lower, std::span<double> x_upper, std::span<double> g_lower,
              std::span<double> g_upper) const override;
  void startingPoint(std::span<double> x) const override;
  double objective(std::span<const double> x) override;
  void gradient(std::span<const double> x, std::span<double> gradient) override;
  void constraints(std::span<const double> x, std::span<double> g) override;
  SparsityEntries constraintJacobianPattern() const override;
  void constraintJacobian(std::span<const double> x, std::span<double> values) override;
  SparsityEntries hessianPattern() const override;
  void hessian(std::span<const double> x, double objective_factor, std::span<const double> multipliers,
               std::span<double> values) override;
  bool iterationDone(const IterationInfo& info) override;

  int knots() const;
  double timeStep() const;
  int velocityConstraintCount() const;  // the first rows of g; the torque rows follow

  // The trajectory, its cost and its limit violations at x (T nv positions).
  Trajectory trajectoryAt(std::span<const double> x);
  TrajectoryCost costAt(std::span<const double> x);
  LimitViolation violationAt(std::span<const double> x);

  // Time spent evaluating the generated functions and assembling derivatives, and how
  // many batches of each order were evaluated.
  double evaluationSeconds() const;
  int firstOrderEvaluations() const;
  int secondOrderEvaluations() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace robodiff::batch
