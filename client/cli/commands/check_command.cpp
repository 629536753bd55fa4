// `robodiff check`: a spec's function, generated (or interpreted), cross-checked at
// random states against what does not share its code: the value against core/dynamics
// in double (a user function's: the double evaluation of its expressions), derivatives
// against central finite differences of it, and the generated code against the
// interpreter.
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands/commands.hpp"
#include "options/function_backends.hpp"
#include "options/function_options.hpp"
#include "output/output_table.hpp"
#include "robodiff/functions/spec_check.hpp"

namespace robodiff::cli {
namespace {

struct CheckArgs {
  RobotArgs robot;
  std::string spec, backend = "generated";
  int samples = 10;
  std::uint64_t seed = 1;
  bool json = false;
};

std::string scientific(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2e", x);
  return buf;
}

void printTable(const std::vector<SpecComparison>& rows, std::ostream& out) {
  Table table = Table::rows({"output", "compared against", "worst abs", "worst rel", "at", "tolerance", "result"},
                            {false, false, true, true, false, true, false});
  for (const SpecComparison& c : rows)
    table.addRow({c.output, c.against, scientific(c.worst_abs), scientific(c.worst_rel),
                  "state " + std::to_string(c.state) + " (seed " + std::to_string(c.seed) + "), [" +
                      std::to_string(c.row) + ", " + std::to_string(c.col) + "]",
                  scientific(c.tolerance), c.pass() ? "PASS" : "FAIL"});
  table.print(out);
}

nlohmann::json rowsJson(const std::vector<SpecComparison>& rows) {
  nlohmann::json out = nlohmann::json::array();
  for (const SpecComparison& c : rows)
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
  // The function under test, and the interpreter beside generated code.
  const BlockEvaluator tested = [&](const std::vector<Eigen::VectorXd>& r) { return f.evaluate(backend, r); };
  BlockEvaluator interpreted;
  if (backend == Backend::Generated)
    interpreted = [&](const std::vector<Eigen::VectorXd>& r) { return f.evaluate(Backend::Interpreted, r); };
  const std::vector<SpecComparison> rows =
      checkSpecFunction(model, f.spec(), f.built(), tested, interpreted, {args.samples, args.seed});
  int failed = 0;
  for (const SpecComparison& c : rows) failed += c.pass() ? 0 : 1;
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
