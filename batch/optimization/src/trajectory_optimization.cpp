// optimizeTrajectory: checks the options, poses the TrajectoryProgram to Ipopt and reads
// the trajectory, its cost and its limit violations back at the final point.
#include "robodiff/batch/trajectory_optimization.hpp"

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "robodiff/batch/trajectory_optimization_functions.hpp"
#include "robodiff/batch/trajectory_optimization_program.hpp"

namespace robodiff::batch {
namespace {

std::string text(double value) {
  std::ostringstream out;
  out.precision(8);
  out << value;
  return out.str();
}

void fail(const std::string& message) { throw std::invalid_argument("trajectory optimisation: " + message); }

// q0 and qT: one finite value per joint, within the joint's position limits.
void checkConfiguration(const Model& model, const Eigen::VectorXd& q, const char* field) {
  if (q.size() != model.nq)
    fail(std::string(field) + " has " + std::to_string(q.size()) + " values, but " +
         (model.name.empty() ? "the robot" : model.name) + " has " + std::to_string(model.nq) + " joint positions");
  const Eigen::VectorXd lower = model.lowerPositionLimit(), upper = model.upperPositionLimit();
  for (const Joint& joint : model.joints)
    for (int i = joint.idx_q; i < joint.idx_q + joint.nq; ++i) {
      if (!std::isfinite(q[i]))
        fail(std::string(field) + ": joint '" + joint.name + "' = " + text(q[i]) + " is not a finite number");
      if (q[i] < lower[i] || q[i] > upper[i])
        fail(std::string(field) + ": joint '" + joint.name + "' = " + text(q[i]) + " is outside its position limits [" +
             text(lower[i]) + ", " + text(upper[i]) + "]");
    }
}

void checkWeight(double value, const char* field) {
  if (!std::isfinite(value) || value < 0) fail(std::string(field) + " = " + text(value) + ": must be finite and >= 0");
}

}  // namespace

void checkTrajectoryOptions(const Model& model, const TrajectoryOptimizationOptions& o) {
  if (model.root != RootJoint::Fixed || model.nq != model.nv)
    fail("needs a fixed-base robot with one position per joint; " + (model.name.empty() ? "the robot" : model.name) +
         " has a floating base or multi-coordinate joints");
  if (model.nv == 0) fail("the robot has no moving joints");
  if (o.knots < 3) fail("knots = " + std::to_string(o.knots) + ": at least 3 are needed (both ends and one between)");
  if (!std::isfinite(o.duration) || o.duration <= 0)
    fail("duration = " + text(o.duration) + ": must be a positive number of seconds");
  checkWeight(o.smoothness_weight, "smoothness_weight");
  checkWeight(o.torque_weight, "torque_weight");
  checkConfiguration(model, o.q0, "q0");
  checkConfiguration(model, o.qT, "qT");
  if (o.initial_guess.size() != 0) {
    if (o.initial_guess.rows() != o.knots || o.initial_guess.cols() != model.nq)
      fail("initial_guess is " + std::to_string(o.initial_guess.rows()) + " x " +
           std::to_string(o.initial_guess.cols()) +
           ", not knots x joints = " + std::to_string(o.knots) + " x " + std::to_string(model.nq));
    if (!o.initial_guess.allFinite()) fail("initial_guess holds a value that is not a finite number");
    const double tolerance = 1e-9;
    if ((o.initial_guess.row(0).transpose() - o.q0).cwiseAbs().maxCoeff() > tolerance)
      fail("initial_guess's first knot differs from q0 (the ends are fixed)");
    if ((o.initial_guess.row(o.knots - 1).transpose() - o.qT).cwiseAbs().maxCoeff() > tolerance)
      fail("initial_guess's last knot differs from qT (the ends are fixed)");
  }
  if (o.effort_limit.size() != 0) {
    if (o.effort_limit.size() != model.nv)
      fail("effort_limit has " + std::to_string(o.effort_limit.size()) + " values, not one per joint (" +
           std::to_string(model.nv) + ")");
    for (int i = 0; i < model.nv; ++i)
      if (std::isnan(o.effort_limit[i]) || o.effort_limit[i] <= 0)
        fail("effort_limit[" + std::to_string(i) + "] = " + text(o.effort_limit[i]) +
             ": must be > 0 (+inf for no limit)");
  }
}

TrajectoryOptimizationResult optimizeTrajectory(const Model& model, const TrajectoryFunctions& functions,
                                                const TrajectoryOptimizationOptions& options) {
  TrajectoryProgram program(model, functions, options);
  std::vector<double> x(static_cast<std::size_t>(program.variableCount()));
  program.startingPoint(x);
  TrajectoryOptimizationResult result;
  result.initial_cost = program.costAt(x);

  const double seconds_before = program.evaluationSeconds();
  const int first_before = program.firstOrderEvaluations(), second_before = program.secondOrderEvaluations();
  const IpoptResult solved = solveWithIpopt(program, options.ipopt);
  result.success = solved.success;
  result.status = solved.status;
  result.iterations = solved.iterations;
  result.cancelled = solved.cancelled;
  result.solve_seconds = solved.seconds;
  result.max_constraint_violation = solved.constraint_violation;
  result.evaluation_seconds = program.evaluationSeconds() - seconds_before;
  result.first_order_evaluations = program.firstOrderEvaluations() - first_before;
  result.second_order_evaluations = program.secondOrderEvaluations() - second_before;

  if (solved.x.size() == x.size()) x = solved.x;  // else (stopped before a point): the start
  result.trajectory = program.trajectoryAt(x);
  result.cost = program.costAt(x);
  result.violation = program.violationAt(x);
  return result;
}

TrajectoryOptimizationResult optimizeTrajectory(const Model& model, const std::string& urdf_text,
                                                const TrajectoryOptimizationOptions& options,
                                                const BatchFunctionOptions& function_options) {
  checkTrajectoryOptions(model, options);  // before a build that may take seconds
  const auto start = std::chrono::steady_clock::now();
  const TrajectoryFunctions functions = TrajectoryFunctions::open(model, urdf_text, function_options);
  const double setup_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  TrajectoryOptimizationResult result = optimizeTrajectory(model, functions, options);
  result.setup_seconds = setup_seconds;
  return result;
}

Eigen::VectorXd centreOfLimits(const Model& model) {
  const Eigen::VectorXd lo = model.lowerPositionLimit(), hi = model.upperPositionLimit();
  Eigen::VectorXd q(model.nq);
  for (int i = 0; i < model.nq; ++i) q[i] = std::isfinite(lo[i]) && std::isfinite(hi[i]) ? (lo[i] + hi[i]) / 2 : 0.0;
  return q;
}

}  // namespace robodiff::batch
