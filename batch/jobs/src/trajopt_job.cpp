// Job kind "trajopt": a trajectory from q0 to qT optimised with Ipopt.
//
// Parameters: "urdf" (path) or "urdf_text", "q0", "qT" (arrays of nq numbers; q0 defaults
// to the middle of each joint's limits), "knots" (50), "duration" (2 s),
// "torque_weight" (1e-3), "smoothness_weight" (1), "velocity_limits" (true),
// "torque_limits" (false), "max_iterations" (3000), "backend" (compiled | interpreted).
// Files: trajectory.csv (t, q_<joint>, v_<joint>, a_<joint>, tau_<joint> per knot).
#include <cmath>

#include "job_kinds.hpp"
#include "job_params.hpp"
#include "robodiff/batch/trajectory_optimization.hpp"
#include "robodiff/batch/trajectory_optimization_csv.hpp"

namespace robodiff::batch {
namespace {

Eigen::VectorXd vectorParam(const nlohmann::json& p, const char* field, int size) {
  const auto it = p.find(field);
  if (it == p.end() || !it->is_array())
    throw JobParamsError(std::string("the job needs \"") + field + "\", an array of " + std::to_string(size) + " numbers");
  if (static_cast<int>(it->size()) != size)
    throw JobParamsError(std::string(field) + " has " + std::to_string(it->size()) + " numbers; the robot has nq = " +
                         std::to_string(size));
  Eigen::VectorXd v(size);
  for (int i = 0; i < size; ++i) {
    if (!(*it)[i].is_number()) throw JobParamsError(std::string(field) + "[" + std::to_string(i) + "] is not a number");
    v[i] = (*it)[i].get<double>();
  }
  return v;
}

TrajectoryOptimizationOptions optionsFrom(const nlohmann::json& p, const Model& model) {
  TrajectoryOptimizationOptions o;
  o.knots = static_cast<int>(params::optionalNumber(p, "knots", o.knots));
  o.duration = params::optionalNumber(p, "duration", o.duration);
  o.torque_weight = params::optionalNumber(p, "torque_weight", o.torque_weight);
  o.smoothness_weight = params::optionalNumber(p, "smoothness_weight", o.smoothness_weight);
  o.velocity_limits = params::optionalBool(p, "velocity_limits", o.velocity_limits);
  o.torque_limits = params::optionalBool(p, "torque_limits", o.torque_limits);
  o.ipopt.max_iterations = static_cast<int>(params::optionalNumber(p, "max_iterations", o.ipopt.max_iterations));
  o.qT = vectorParam(p, "qT", model.nq);
  o.q0 = p.contains("q0") ? vectorParam(p, "q0", model.nq) : centreOfLimits(model);
  try {
    checkTrajectoryOptions(model, o);
  } catch (const std::invalid_argument& e) {
    throw JobParamsError(e.what());
  }
  return o;
}

}  // namespace

void validateTrajoptParams(const nlohmann::json& p, const FileAccess& files) {
  params::checkRobotFields(p, files);
  params::backend(p);
  optionsFrom(p, params::robot(p, files).model);  // cheap: parses the URDF, checks q0/qT against its limits
}

nlohmann::json runTrajoptKind(const nlohmann::json& p, const BatchJobContext& context) {
  const params::Robot robot = params::robot(p, context.files);
  TrajectoryOptimizationOptions options = optionsFrom(p, robot.model);
  const int max_iterations = options.ipopt.max_iterations;
  options.on_iteration = [&](const IterationInfo& info) {
    if (context.progress)
      context.progress(std::min(0.95, 0.05 + 0.9 * info.iteration / std::max(1, max_iterations)),
                       "iteration " + std::to_string(info.iteration) + ": cost " + std::to_string(info.objective) +
                           ", infeasibility " + std::to_string(info.primal_infeasibility));
    return true;
  };
  BatchFunctionOptions functions;
  functions.backend = params::backend(p);
  functions.cache_dir = context.cache_dir;
  if (context.progress) context.progress(0.0, "building the functions");
  const TrajectoryOptimizationResult r = optimizeTrajectory(robot.model, robot.urdf_text, options, functions);
  writeTrajectoryCsvFile(context.result_dir / "trajectory.csv", r.trajectory, robot.model.jointNames());
  if (!r.success)
    throw std::runtime_error("Ipopt did not succeed: " + r.status + " after " + std::to_string(r.iterations) +
                             " iterations (max constraint violation " + std::to_string(r.max_constraint_violation) +
                             ")");
  if (context.progress) context.progress(1.0, r.status);
  return {{"kind", "trajopt"},
          {"status", r.status},
          {"iterations", r.iterations},
          {"knots", options.knots},
          {"cost", {{"smoothness", r.cost.smoothness}, {"torque", r.cost.torque}, {"total", r.cost.total}}},
          {"initial_cost", r.initial_cost.total},
          {"violation", {{"position", r.violation.position}, {"velocity", r.violation.velocity}, {"torque", r.violation.torque}}},
          {"seconds", {{"setup", r.setup_seconds}, {"solve", r.solve_seconds}, {"functions", r.evaluation_seconds}}},
          {"out", "trajectory.csv"}};
}

}  // namespace robodiff::batch
