#pragma once
// Trajectory optimisation of a fixed-base robot through Ipopt, with exact gradients and
// exact sparse Hessians assembled from generated code (inverse dynamics, its Jacobian
// and its weighted Hessian; trajectory_optimization_functions.hpp).
//
// The problem, from q0 to qT in T knots over `duration` seconds:
//
//   variables    x = [q_0; q_1; ...; q_{T-1}] (T nv); q_0 = q0 and q_{T-1} = qT are fixed
//                by equal bounds (Ipopt treats fixed variables as parameters), so every
//                knot keeps one formula and the result holds both ends.
//   differences  h = duration / (T - 1), central in every knot:
//                  v_k = (q_{k+1} - q_{k-1}) / (2h),  a_k = (q_{k+1} - 2 q_k + q_{k-1}) / h^2,
//                with mirrored ghost knots q_{-1} = q_1 and q_T = q_{T-2}: the robot is at
//                rest at both ends (v_0 = v_{T-1} = 0) and may accelerate away from them
//                (a_0 = 2 (q_1 - q_0) / h^2), so the ends constrain their neighbours.
//   cost         J = smoothness_weight * sum_k c_k |a_k|^2 + torque_weight * sum_k c_k |tau_k|^2,
//                tau_k = RNEA(q_k, v_k, a_k), c_k the trapezoidal rule (h, h/2 at the ends).
//   constraints  position limits as variable bounds (interior knots; continuous joints
//                unbounded); velocity limits |v_k| <= vmax (the URDF's, finite ones) as
//                linear constraints on the interior knots; optionally torque limits
//                |tau_k| <= effort on every knot as nonlinear constraints.
//
// The derivatives and the Hessian's band are described in trajectory_optimization_program.hpp.

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "robodiff/batch/batch_function.hpp"
#include "robodiff/batch/ipopt_solver.hpp"
#include "robodiff/batch/nonlinear_program.hpp"
#include "robodiff/model/model.hpp"

namespace robodiff::batch {

class TrajectoryFunctions;

struct TrajectoryOptimizationOptions {
  int knots = 50;                  // T >= 3, both ends included
  double duration = 2.0;           // seconds from q0 to qT
  double smoothness_weight = 1.0;  // on sum_k c_k |a_k|^2
  double torque_weight = 1e-3;     // w, on sum_k c_k |tau_k|^2
  Eigen::VectorXd q0, qT;          // nq each, within the position limits
  Eigen::MatrixXd initial_guess;   // T x nq, rows q0 .. qT; empty: the straight line from q0 to qT
  bool velocity_limits = true;     // |v_k| <= the URDF's velocity limits
  bool torque_limits = false;      // |tau_k| <= effort_limit
  Eigen::VectorXd effort_limit;    // nv; empty: the URDF's effort limits (+inf where it gives none)
  IpoptOptions ipopt;
  // After each Ipopt iteration (progress); returning false cancels the solve.
  std::function<bool(const IterationInfo&)> on_iteration;
};

// The knots of a trajectory, one row per knot.
struct Trajectory {
  Eigen::VectorXd time;          // T, t_k = k h
  Eigen::MatrixXd q, v, a, tau;  // T x nv
};

struct TrajectoryCost {
  double smoothness = 0;  // smoothness_weight * sum_k c_k |a_k|^2
  double torque = 0;      // torque_weight * sum_k c_k |tau_k|^2
  double total = 0;
};

// By how much the worst knot exceeds a limit (0: within). Velocities and torques are
// measured against the URDF's velocity limits and the effort limits whether or not they
// were enforced.
struct LimitViolation {
  double position = 0, velocity = 0, torque = 0;
};

struct TrajectoryOptimizationResult {
  bool success = false;      // Ipopt solved to tolerance (or to its acceptable level)
  std::string status;        // Ipopt's return, e.g. "Solve_Succeeded"
  int iterations = 0;
  bool cancelled = false;    // on_iteration returned false
  Trajectory trajectory;     // at Ipopt's final point (also on failure)
  TrajectoryCost cost;       // at the final point
  TrajectoryCost initial_cost;  // at the starting point (the straight line by default)
  LimitViolation violation;
  double max_constraint_violation = 0;  // Ipopt's: bounds and enforced constraints
  // Time: opening (building or loading) the functions, the whole Ipopt solve, and the
  // part of it spent evaluating the generated functions and assembling derivatives.
  double setup_seconds = 0, solve_seconds = 0, evaluation_seconds = 0;
  int first_order_evaluations = 0;   // knots' tau and Jacobian, once per new x
  int second_order_evaluations = 0;  // knots' weighted Hessians, once per Hessian
};

// The centre of every joint's position limits (0 where it has none): q0's default in the
// CLI and in jobs (a neutral pose may lie outside the limits, as the Panda's joint 4 does).
Eigen::VectorXd centreOfLimits(const Model& model);

// Throws std::invalid_argument naming the field and value when the options do not fit
// the model (a floating base, T < 3, a duration <= 0, negative weights, q0 or qT of the
// wrong size or outside a joint's limits, an initial guess of the wrong shape or ends).
void checkTrajectoryOptions(const Model& model, const TrajectoryOptimizationOptions& options);

// Solves with functions already opened (tests, benches and repeated solves share them).
TrajectoryOptimizationResult optimizeTrajectory(const Model& model, const TrajectoryFunctions& functions,
                                                const TrajectoryOptimizationOptions& options);

// Opens the functions (compiled through the cache, or interpreted), then solves.
// `urdf_text` is the text `model` was loaded from.
TrajectoryOptimizationResult optimizeTrajectory(const Model& model, const std::string& urdf_text,
                                                const TrajectoryOptimizationOptions& options,
                                                const BatchFunctionOptions& function_options = {});

}  // namespace robodiff::batch
