// `robodiff check`: a spec's function, generated (or interpreted), cross-checked at
// random states against what does not share its code: the value against core/dynamics
// in double (a user function's: the double evaluation of its expressions), derivatives
// against central finite differences of it, and the generated code against the
// interpreter.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands/commands.hpp"
#include "options/function_backends.hpp"
#include "options/function_options.hpp"
#include "output/output_table.hpp"
#include "robodiff/functions/reference.hpp"

namespace robodiff::cli {
namespace {

struct CheckArgs {
  RobotArgs robot;
  std::string spec, backend = "generated";
  int samples = 10;
  std::uint64_t seed = 1;
  bool json = false;
};

// Tolerances on the relative error (see Comparison). Functions that invert the mass
// matrix lose digits with its condition number; finite differences carry truncation and
// rounding errors of about h^2 and eps/h (h^2 and eps/h^2 for second differences).
// Compiled code may fuse a*b + c into one FMA (rounded once, -march=native), the
// interpreter rounds twice: the two agree to rounding, amplified like the values.
constexpr double kValueTolerance = 1e-10, kInvertingValueTolerance = 1e-9;
constexpr double kJacobianTolerance = 1e-5, kHessianTolerance = 1e-4;
constexpr double kBackendTolerance = 1e-11, kInvertingBackendTolerance = 1e-9;
// A user function may invert the mass matrix anywhere (aba, minv), so its values and
// backends are held to the inverting tolerances; its expressions are arbitrary, with
// larger higher-order terms in the differences' truncation error.
constexpr double kUserDerivativeTolerance = 1e-4, kUserHessianTolerance = 1e-3;

// One output block against one expectation over all states: the worst absolute and
// relative error and where the relative one is. Relative errors are elementwise,
// relative to max(|expected|, 1e-3 max|expected|, 1e-6) (as tests/support/golden.cpp's
// matricesAgree), so entries near zero are not judged on noise.
struct Comparison {
  std::string output, against;
  double tolerance = 0;
  double worst_abs = 0, worst_rel = 0;
  int state = -1;  // index of the state with the worst relative error
  std::uint64_t seed = 0;
  Eigen::Index row = 0, col = 0;

  bool pass() const { return worst_rel <= tolerance; }

  void add(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected, int state_index, std::uint64_t state_seed) {
    if (actual.rows() != expected.rows() || actual.cols() != expected.cols())
      throw std::logic_error("check: " + output + " is " + std::to_string(actual.rows()) + " x " +
                             std::to_string(actual.cols()) + ", expected " + std::to_string(expected.rows()) + " x " +
                             std::to_string(expected.cols()));
    const double floor = std::max(1e-6, 1e-3 * (expected.size() ? expected.cwiseAbs().maxCoeff() : 0.0));
    for (Eigen::Index r = 0; r < expected.rows(); ++r)
      for (Eigen::Index c = 0; c < expected.cols(); ++c) {
        double abs = std::abs(actual(r, c) - expected(r, c));
        if (std::isnan(abs)) abs = std::numeric_limits<double>::infinity();  // NaN fails
        const double rel = abs / std::max(std::abs(expected(r, c)), floor);
        worst_abs = std::max(worst_abs, abs);
        if (state < 0 || rel > worst_rel) worst_rel = rel, state = state_index, seed = state_seed, row = r, col = c;
      }
  }
};

std::string scientific(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2e", x);
  return buf;
}

// Output k against its reference: what the reference is, and the tolerance.
Comparison referenceComparison(const FunctionSpec& spec, std::size_t k, const std::string& name) {
  if (spec.isUser()) {
    switch (spec.user->outputs[k].kind) {
      case UserOutputKind::Value: return {name, "double evaluation", kInvertingValueTolerance};
      case UserOutputKind::Hessian: return {name, "second finite differences", kUserHessianTolerance};
      default: return {name, "finite differences", kUserDerivativeTolerance};  // Jacobian, gradient, vjp
    }
  }
  const bool inverting = spec.function == ModelFunction::Aba || spec.function == ModelFunction::Minv;
  switch (spec.outputs[k].kind) {
    case OutputKind::Value:
      return {name, "reference (core/dynamics)", inverting ? kInvertingValueTolerance : kValueTolerance};
    case OutputKind::Jacobian: return {name, "finite differences", kJacobianTolerance};
    case OutputKind::Hessian: return {name, "second finite differences", kHessianTolerance};
  }
  return {name, "?", 0.0};
}

// Output k of the generated code against the interpreter.
Comparison backendComparison(const FunctionSpec& spec, const std::string& name) {
  const bool inverting =
      spec.isUser() || spec.function == ModelFunction::Aba || spec.function == ModelFunction::Minv;
  return {name, "interpreted", inverting ? kInvertingBackendTolerance : kBackendTolerance};
}

// Every output's reference at the runtime inputs, in the layout of the built blocks.
std::vector<Eigen::MatrixXd> referenceOutputs(const Model& model, const SpecFunction& f,
                                              const std::vector<Eigen::VectorXd>& runtime) {
  const FunctionSpec& spec = f.spec();
  const std::vector<Eigen::VectorXd> all = f.allInputs(runtime);
  if (spec.isUser()) return userReferenceOutputs(model, spec, all);
  std::vector<Eigen::MatrixXd> out;
  for (std::size_t k = 0; k < spec.outputs.size(); ++k) {
    const OutputSpec& o = spec.outputs[k];
    if (o.kind == OutputKind::Value) out.push_back(f.valueMatrix(referenceValue(model, spec, all)));
    else if (o.kind == OutputKind::Jacobian) out.push_back(finiteDifferenceJacobian(model, spec, all, o.wrt));
    else out.push_back(finiteDifferenceHessian(model, spec, all, f.hessianWeights(k, runtime), o.wrt));
  }
  return out;
}

std::vector<Comparison> runChecks(const Model& model, const SpecFunction& f, Backend backend, const CheckArgs& args) {
  const FunctionSpec& spec = f.spec();
  const std::size_t n = spec.outputs.size();
  const bool against_interpreter = backend == Backend::Generated;
  std::vector<Comparison> rows;  // per output: against the reference, then the interpreter
  for (std::size_t k = 0; k < n; ++k) {
    const std::string& name = f.built().outputs[k].name;
    rows.push_back(referenceComparison(spec, k, name));
    if (against_interpreter) rows.push_back(backendComparison(spec, name));
  }
  const std::size_t per_output = against_interpreter ? 2 : 1;
  for (int s = 0; s < args.samples; ++s) {
    const std::uint64_t seed = args.seed + static_cast<std::uint64_t>(s);
    const std::vector<Eigen::VectorXd> runtime = randomRuntimeInputs(model, spec, seed);
    const std::vector<Eigen::MatrixXd> got = f.evaluate(backend, runtime);
    const std::vector<Eigen::MatrixXd> expected = referenceOutputs(model, f, runtime);
    std::vector<Eigen::MatrixXd> interpreted;
    if (against_interpreter) interpreted = f.evaluate(Backend::Interpreted, runtime);
    for (std::size_t k = 0; k < n; ++k) {
      rows[k * per_output].add(got[k], expected[k], s, seed);
      if (against_interpreter) rows[k * per_output + 1].add(got[k], interpreted[k], s, seed);
    }
  }
  return rows;
}

void printTable(const std::vector<Comparison>& rows, std::ostream& out) {
  Table table = Table::rows({"output", "compared against", "worst abs", "worst rel", "at", "tolerance", "result"},
                            {false, false, true, true, false, true, false});
  for (const Comparison& c : rows)
    table.addRow({c.output, c.against, scientific(c.worst_abs), scientific(c.worst_rel),
                  "state " + std::to_string(c.state) + " (seed " + std::to_string(c.seed) + "), [" +
                      std::to_string(c.row) + ", " + std::to_string(c.col) + "]",
                  scientific(c.tolerance), c.pass() ? "PASS" : "FAIL"});
  table.print(out);
}

nlohmann::json rowsJson(const std::vector<Comparison>& rows) {
  nlohmann::json out = nlohmann::json::array();
  for (const Comparison& c : rows)
    out.push_back({{"output", c.output},
                   {"against", c.against},
                   {"worst_abs_error", c.worst_abs},
                   {"worst_rel_error", c.worst_rel},
                   {"state", c.state},
                   {"seed", c.seed},
                   {"row", c.row},
                   {"col", c.col},
                   {"tolerance", c.tolerance},
                   {"pass", c.pass()}});
  return out;
}

void runCheck(const CheckArgs& args) {
  const Model model = loadRobot(args.robot);
  const FunctionSpec spec = loadFunctionSpec(args.spec);
  const Backend backend = parseBackend(args.backend);
  const SpecFunction f(model, spec,
                       backend == Backend::Generated ? std::vector{Backend::Generated, Backend::Interpreted}
                                                     : std::vector{Backend::Interpreted});
  const std::vector<Comparison> rows = runChecks(model, f, backend, args);
  int failed = 0;
  for (const Comparison& c : rows) failed += c.pass() ? 0 : 1;
  if (args.json) {
    nlohmann::json j = {{"function", f.definition().name},
                        {"backend", args.backend},
                        {"nq", model.nq},
                        {"nv", model.nv},
                        {"samples", args.samples},
                        {"seed", args.seed},
                        {"pass", failed == 0},
                        {"comparisons", rowsJson(rows)}};
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << "check " << f.definition().name << " on " << (model.name.empty() ? args.robot.urdf : model.name)
              << " (nq = " << model.nq << ", nv = " << model.nv << "): " << args.backend << " backend, " << args.samples
              << " random states from seed " << args.seed << "\n";
    printTable(rows, std::cout);
    std::cout << (failed ? std::to_string(failed) + " of " + std::to_string(rows.size()) + " comparisons FAIL"
                         : "all " + std::to_string(rows.size()) + " comparisons pass")
              << "\n";
  }
  std::cout.flush();
  if (failed) throw CLI::RuntimeError(2);  // main returns the exit code without a message
}

}  // namespace

void addCheckCommand(CLI::App& app) {
  auto args = std::make_shared<CheckArgs>();
  CLI::App* cmd = app.add_subcommand(
      "check", "Cross-check a generated function against the double reference and finite differences");
  addRobotOptions(*cmd, args->robot);
  addSpecOption(*cmd, args->spec, true);
  cmd->add_option("--samples", args->samples, "Random states to check at (default 10)")
      ->check(CLI::PositiveNumber)
      ->type_name("N");
  cmd->add_option("--seed", args->seed, "Seed of the first random state; state i uses seed S + i (default 1)")
      ->type_name("S");
  cmd->add_option("--backend", args->backend,
                  "generated (default): compile the function (in a temporary directory) and check it, and compare "
                  "it with the interpreter too; interpreted: check the interpreter alone, nothing compiled")
      ->check(CLI::IsMember({"generated", "interpreted"}));
  cmd->add_flag("--json", args->json, "Print the comparisons as JSON instead of a table");
  cmd->footer(
      "Comparisons, per output block, with the worst error over all states: the value against core/dynamics "
      "in double (relative tolerance 1e-10; 1e-9 for aba and minv, which invert the mass matrix); Jacobians "
      "against central finite differences (1e-5); Hessians against second central differences (1e-4); the "
      "generated code against the interpreter (1e-11; 1e-9 for aba and minv: compiled code may fuse a*b + c into "
      "one FMA instruction, rounded once). A user spec's outputs, by their names: values against the double "
      "evaluation of the same expressions (1e-9), Jacobians, gradients and vector-Jacobian products against "
      "central finite differences of it (1e-4), Hessians against second differences (1e-3), the generated code "
      "against the interpreter (1e-9). Relative errors are elementwise, relative to "
      "max(|expected|, 1e-3 max|expected|, 1e-6).\n"
      "Exit status: 0 when every comparison passes, 2 when one or more fail, 1 on errors (bad spec, unknown "
      "frame, compile failure, ...).");
  cmd->callback([args] { runCheck(*args); });
}

}  // namespace robodiff::cli
