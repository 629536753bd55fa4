// `robodiff trajopt`: trajectory optimisation of a fixed-base robot from q0 to qT through
// Ipopt, with exact derivatives from generated code (batch/optimization,
// trajectory_optimization.hpp), printed as a summary or JSON, the knots written as CSV.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "options/batch_function_options.hpp"
#include "service/service_helpers.hpp"
#include "commands/commands.hpp"
#include "robodiff/batch/trajectory_optimization.hpp"
#include "robodiff/batch/trajectory_optimization_csv.hpp"
#include "robodiff/model/urdf_loader.hpp"
#include "output/state_json.hpp"

namespace robodiff::cli {
namespace {

struct TrajoptArgs {
  std::string urdf, q0, qT, out;
  BatchFunctionArgs function;
  int knots = 50, max_iterations = 3000, print_level = 0;
  double duration = 2.0, torque_weight = 1e-3, smoothness_weight = 1.0, tolerance = 1e-8;
  bool no_velocity_limits = false, torque_limits = false, json = false;
  std::vector<std::string> ipopt_options;  // NAME=VALUE
};

// --q0 / --qT: "v1,v2,..." (commas or spaces), or a state file STATE.json whose "q" is used.
Eigen::VectorXd parseConfiguration(const std::string& text, const std::string& flag) {
  if (text.size() > 5 && text.substr(text.size() - 5) == ".json") {
    const State state = readStateFile(text);
    if (!state.q) throw std::invalid_argument(flag + ": the state file " + text + " has no \"q\"");
    return *state.q;
  }
  std::vector<double> values;
  std::string field;
  std::istringstream in(text);
  while (in >> std::ws && !in.eof()) {
    field.clear();
    while (in.peek() != EOF && in.peek() != ',' && !std::isspace(in.peek())) field += static_cast<char>(in.get());
    if (in.peek() == ',') in.get();
    if (field.empty()) continue;
    std::size_t used = 0;
    double value = 0;
    try {
      value = std::stod(field, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != field.size() || !std::isfinite(value))
      throw std::invalid_argument(flag + ": '" + field + "' in '" + text + "' is not a finite number");
    values.push_back(value);
  }
  if (values.empty()) throw std::invalid_argument(flag + ": no values in '" + text + "'");
  return Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

nlohmann::json costJson(const batch::TrajectoryCost& c) {
  return {{"total", c.total}, {"smoothness", c.smoothness}, {"torque", c.torque}};
}

std::string number(double value, int precision = 4) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", precision, value);
  return buffer;
}

void printSummary(std::ostream& out, const Model& model, const TrajoptArgs& args,
                  const batch::TrajectoryOptimizationOptions& options, const batch::TrajectoryOptimizationResult& r) {
  const double h = options.duration / (options.knots - 1);
  out << "trajopt " << (model.name.empty() ? args.urdf : model.name) << ": " << options.knots << " knots over "
      << number(options.duration) << " s (h = " << number(h) << " s), torque weight " << number(options.torque_weight)
      << ", smoothness weight " << number(options.smoothness_weight) << ", " << args.function.backend << " backend\n";
  out << "  status         " << r.status << " after " << r.iterations << " iterations"
      << (r.cancelled ? " (cancelled)" : "") << "\n";
  out << "  time           solve " << number(r.solve_seconds) << " s, of which function evaluations "
      << number(r.evaluation_seconds) << " s (" << r.first_order_evaluations << " first-order and "
      << r.second_order_evaluations << " second-order batches); setup " << number(r.setup_seconds) << " s\n";
  out << "  cost           " << number(r.cost.total, 6) << " = smoothness " << number(r.cost.smoothness, 6)
      << " + torque " << number(r.cost.torque, 6) << " (straight line: " << number(r.initial_cost.total, 6) << ")\n";
  out << "  max violation  position " << number(r.violation.position) << ", velocity "
      << number(r.violation.velocity) << (options.velocity_limits ? "" : " (not enforced)") << ", torque "
      << number(r.violation.torque) << (options.torque_limits ? "" : " (not enforced)") << "\n";
  if (!args.out.empty()) out << "  wrote          " << args.out << "\n";
}

void run(const TrajoptArgs& args) {
  const std::string urdf_text = readTextFile(args.urdf, "--urdf");
  const Model model = loadUrdfString(urdf_text, RootJoint::Fixed, args.urdf);

  batch::TrajectoryOptimizationOptions options;
  options.knots = args.knots;
  options.duration = args.duration;
  options.torque_weight = args.torque_weight;
  options.smoothness_weight = args.smoothness_weight;
  options.q0 = args.q0.empty() ? batch::centreOfLimits(model) : parseConfiguration(args.q0, "--q0");
  options.qT = parseConfiguration(args.qT, "--qT");
  options.velocity_limits = !args.no_velocity_limits;
  options.torque_limits = args.torque_limits;
  options.ipopt.max_iterations = args.max_iterations;
  options.ipopt.tolerance = args.tolerance;
  options.ipopt.print_level = args.print_level;
  for (const std::string& option : args.ipopt_options) {
    const std::size_t equals = option.find('=');
    if (equals == std::string::npos || equals == 0 || equals + 1 == option.size())
      throw std::invalid_argument("--ipopt: '" + option + "' is not NAME=VALUE");
    options.ipopt.extra.emplace_back(option.substr(0, equals), option.substr(equals + 1));
  }

  batch::BatchFunctionOptions functions = batchFunctionOptions(args.function);
  functions.on_progress = [told = std::make_shared<bool>(false)](const std::string& what) {
    if (what != "building" || *told) return;
    *told = true;
    std::cerr << "building the dynamics functions into the cache (once per robot)...\n";
  };
  const batch::TrajectoryOptimizationResult r = batch::optimizeTrajectory(model, urdf_text, options, functions);
  if (!args.out.empty()) batch::writeTrajectoryCsvFile(args.out, r.trajectory, model.jointNames());

  if (args.json) {
    nlohmann::json j = {
        {"robot", model.name},
        {"knots", options.knots},
        {"duration", options.duration},
        {"torque_weight", options.torque_weight},
        {"smoothness_weight", options.smoothness_weight},
        {"backend", batch::toString(functions.backend)},
        {"success", r.success},
        {"status", r.status},
        {"iterations", r.iterations},
        {"cancelled", r.cancelled},
        {"seconds", {{"setup", r.setup_seconds}, {"solve", r.solve_seconds}, {"evaluation", r.evaluation_seconds}}},
        {"evaluations", {{"first_order", r.first_order_evaluations}, {"second_order", r.second_order_evaluations}}},
        {"cost", costJson(r.cost)},
        {"initial_cost", costJson(r.initial_cost)},
        {"max_violation",
         {{"position", r.violation.position}, {"velocity", r.violation.velocity}, {"torque", r.violation.torque}}},
        {"enforced", {{"velocity", options.velocity_limits}, {"torque", options.torque_limits}}},
        {"max_constraint_violation", r.max_constraint_violation}};
    if (!args.out.empty()) j["out"] = args.out;
    std::cout << j.dump() << "\n";
  } else {
    printSummary(std::cout, model, args, options, r);
  }
  if (!r.success) throw CLI::RuntimeError(1);  // main returns 1 without another message
}

}  // namespace

void addTrajoptCommand(CLI::App& app) {
  auto args = std::make_shared<TrajoptArgs>();
  CLI::App* cmd = app.add_subcommand(
      "trajopt", "Optimise a trajectory from q0 to qT: smooth, low torque, within the joint limits (Ipopt)");
  cmd->add_option("--urdf", args->urdf, "Robot description (URDF file; a fixed-base robot)")
      ->required()
      ->type_name("FILE");
  cmd->add_option("--q0", args->q0,
                  "Start configuration: \"v1,v2,...\" (one per joint, in the URDF's joint order) or a state file "
                  "STATE.json (its \"q\"); default the centre of every joint's limits")
      ->type_name("Q|STATE.json");
  cmd->add_option("--qT", args->qT, "Goal configuration, as --q0")->required()->type_name("Q|STATE.json");
  cmd->add_option("--knots", args->knots, "Knots T, both ends included (default 50)")->check(CLI::Range(3, 1000000));
  cmd->add_option("--duration", args->duration, "Seconds from q0 to qT (default 2)");
  cmd->add_option("--torque-weight", args->torque_weight, "w in the cost's w * sum_k h |tau_k|^2 (default 1e-3)");
  cmd->add_option("--smoothness-weight", args->smoothness_weight,
                  "Weight of the cost's sum_k h |a_k|^2 (default 1)");
  cmd->add_flag("--no-velocity-limits", args->no_velocity_limits, "Do not enforce the URDF's velocity limits");
  cmd->add_flag("--torque-limits", args->torque_limits, "Enforce the URDF's effort limits on every knot's torques");
  cmd->add_option("--out", args->out, "Write the knots as CSV: t, q_<joint>..., v_<joint>..., a_<joint>..., "
                                      "tau_<joint>...")
      ->type_name("FILE.csv");
  addBatchFunctionOptions(*cmd, args->function, "knot", /*with_threads=*/true);
  cmd->add_option("--max-iter", args->max_iterations, "Ipopt's iteration limit (default 3000)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--tolerance", args->tolerance, "Ipopt's tol (default 1e-8)")->check(CLI::PositiveNumber);
  cmd->add_option("--print-level", args->print_level, "Ipopt's output on stdout, 0 (default) to 12")
      ->check(CLI::Range(0, 12));
  cmd->add_option("--ipopt", args->ipopt_options,
                  "Any other Ipopt option, e.g. --ipopt mu_strategy=adaptive (repeatable; an option Ipopt rejects is "
                  "an error naming it)")
      ->type_name("NAME=VALUE");
  cmd->add_flag("--json", args->json, "Print the summary as one JSON object");
  cmd->footer(
      "Problem: positions of every knot (the ends fixed to q0 and qT), velocities and accelerations by central "
      "differences with the robot at rest at both ends; cost smoothness_weight * sum h |a|^2 + torque_weight * sum "
      "h |tau|^2 (tau by inverse dynamics); position limits always, velocity limits unless --no-velocity-limits, "
      "effort limits with --torque-limits. Exact gradients and Hessians from generated code.\n"
      "Output (json): {\"success\", \"status\", \"iterations\", \"seconds\": {setup, solve, evaluation}, \"cost\" and "
      "\"initial_cost\": {total, smoothness, torque}, \"max_violation\": {position, velocity, torque}, ...}.\n"
      "Exit status: 0 when Ipopt succeeds, 1 when it does not (the summary is still printed and --out written) or on "
      "errors.");
  cmd->callback([args] { run(*args); });
}

}  // namespace robodiff::cli
